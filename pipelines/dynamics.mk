# Dynamics (thesis ch. 4; docs/dynamics.md).
#
#   make -f Makefile.pipeline dynamics-drops     the 1 cm block dropped face-first from 3 cm with the
#                                                complementarity, DKE and BBI impact models, and obliquely (BBI)
#   make -f Makefile.pipeline dac-cantilever     DAC on the calibration rig: a fine rig (0.75 mm voxels) is the
#                                                reference; its tip track calibrates the 3 mm rig, which runs again
#                                                with the fitted dac_model (minutes)
#   make -f Makefile.pipeline dynamics-flipper   the flipper jumper pressed, released, jumping, flying as a
#                                                rigid body, landing (about half a minute)
#   make -f Makefile.pipeline dynamics-catapult  the catapult throwing a cube that lies in its basket (body
#                                                contact; about a minute)
#   make -f Makefile.pipeline design-flipper     design loops of §4.5.1 (msfab-jump-design, COBYLA starts over
#   make -f Makefile.pipeline design-jump-onto   MPI ranks; docs/design_loop.md): flip to land upright, jump onto
#   make -f Makefile.pipeline design-jump-over   a platform, over a wall, throw the catapult's cube at a target
#   make -f Makefile.pipeline design-catapult    (minutes each; RANKS=2 THREADS=1 on two cores; a killed loop
#                                                resumes from its checkpoints when run again)
#   make -f Makefile.pipeline design-catapult-rim  the catapult with its basket's wall height as a third
#                                                parameter (about 25 minutes on two ranks)
#   make -f Makefile.pipeline design-strips      a side-view strip of each final jump of the design loops run so
#                                                far (out/design/*.strip.png, python3 -m msfab strip)
#   make -f Makefile.pipeline bench-dac-plant    DAC against accurate and convergent meshes on the plant-like
#   make -f Makefile.pipeline bench-dac-jumper   scene and the flipper jumper (tools/bench_dac_*.sh; minutes;
#                                                figures in docs/BENCHMARKS.md, "Dynamics")
#
# Writes out/dynamics/*.trajectory.h5 with .xmf time series and PNG plots,
# out/design/*.jump_design.h5 with the final design's run beside it (*.final.trajectory.h5).
DYN := $(OUT)/dynamics

$(DYN)/drop_face_%.trajectory.h5: configs/dynamics/block_drop_face.yaml $(STAGE_ID)/msfab-dynamics.id
	@mkdir -p $(@D)
	$(BIN)/msfab-dynamics --config $< --set simulation.impact=$* --threads $(THREADS) $(QUIET) --out $@

$(DYN)/drop_oblique.trajectory.h5: configs/dynamics/block_drop_oblique.yaml $(STAGE_ID)/msfab-dynamics.id
	@mkdir -p $(@D)
	$(BIN)/msfab-dynamics --config $< --threads $(THREADS) $(QUIET) --out $@

$(DYN)/rig_fine.trajectory.h5: configs/dynamics/cantilever_pluck.yaml $(STAGE_ID)/msfab-dynamics.id
	@mkdir -p $(@D)
	$(BIN)/msfab-dynamics --config $< --set geometry.voxel_size=0.00075 --set simulation.duration=0.03 \
	  --marker 0.06 0 0.006 --marker-csv $(DYN)/rig_fine_tip.csv --threads $(THREADS) $(QUIET) --out $@

$(DYN)/rig.dac_model.h5: configs/dac/cantilever_from_fine.yaml $(DYN)/rig_fine.trajectory.h5 $(STAGE_ID)/msfab-dac-calibrate.id
	$(BIN)/msfab-dac-calibrate --config $< --set marker_csv=$(abspath $(DYN))/rig_fine_tip.csv --out $@

$(DYN)/rig_dac.trajectory.h5: configs/dynamics/cantilever_dac.yaml $(DYN)/rig.dac_model.h5 $(STAGE_ID)/msfab-dynamics.id
	$(BIN)/msfab-dynamics --config $< --set 'materials[0].dac_model=$(abspath $(DYN))/rig.dac_model.h5' \
	  --marker 0.06 0 0.006 --marker-csv $(DYN)/rig_dac_tip.csv --threads $(THREADS) $(QUIET) --out $@

$(DYN)/flipper.trajectory.h5: configs/dynamics/flipper_jumper.yaml $(STAGE_ID)/msfab-dynamics.id
	@mkdir -p $(@D)
	$(BIN)/msfab-dynamics --config $< --threads $(THREADS) --out $@

$(DYN)/catapult.trajectory.h5: configs/dynamics/catapult.yaml $(STAGE_ID)/msfab-dynamics.id
	@mkdir -p $(@D)
	$(BIN)/msfab-dynamics --config $< --threads $(THREADS) --out $@

$(OUT)/design/%.jump_design.h5: configs/design/%.yaml $(STAGE_ID)/msfab-jump-design.id
	@mkdir -p $(@D)
	OMP_NUM_THREADS=$(THREADS) $(MPIRUN) $(BIN)/msfab-jump-design --config $< --out $@ --resume

# The final run is written with the design artifact.
$(OUT)/design/%.strip.png: $(OUT)/design/%.jump_design.h5
	PYTHONPATH=$(CURDIR)/python $(PYTHON) -m msfab strip $(OUT)/design/$*.final.trajectory.h5 $@ --frames 10

$(OUT)/design/flipper.jump_design.h5: configs/dynamics/flipper_param.yaml
$(OUT)/design/jump_onto.jump_design.h5: configs/dynamics/jumper_onto.yaml
$(OUT)/design/jump_over.jump_design.h5: configs/dynamics/jumper_over.yaml
$(OUT)/design/catapult.jump_design.h5: configs/dynamics/catapult_param.yaml
$(OUT)/design/catapult_rim.jump_design.h5: configs/dynamics/catapult_param.yaml

.PHONY: dynamics-drops dac-cantilever dynamics-flipper design-flipper design-jump-onto design-jump-over design-catapult design-catapult-rim dynamics-catapult \
    bench-dac-plant bench-dac-jumper
dynamics-drops: stages $(DYN)/drop_face_complementarity.trajectory.h5 $(DYN)/drop_face_dke.trajectory.h5 \
    $(DYN)/drop_face_bbi.trajectory.h5 $(DYN)/drop_oblique.trajectory.h5
dac-cantilever: stages $(DYN)/rig_dac.trajectory.h5
dynamics-flipper: stages $(DYN)/flipper.trajectory.h5
dynamics-catapult: stages $(DYN)/catapult.trajectory.h5
design-flipper: stages $(OUT)/design/flipper.jump_design.h5
design-jump-onto: stages $(OUT)/design/jump_onto.jump_design.h5
design-jump-over: stages $(OUT)/design/jump_over.jump_design.h5
design-catapult: stages $(OUT)/design/catapult.jump_design.h5
design-catapult-rim: stages $(OUT)/design/catapult_rim.jump_design.h5
.PHONY: design-strips
design-strips:
	@test -n "$(wildcard $(OUT)/design/*.jump_design.h5)" || \
	  { echo "msfab: no design loop has run yet (make -f Makefile.pipeline design-flipper, ...)" >&2; exit 2; }
	@$(MAKE) -f $(firstword $(MAKEFILE_LIST)) --no-print-directory \
	  $(patsubst %.jump_design.h5,%.strip.png,$(wildcard $(OUT)/design/*.jump_design.h5))
bench-dac-plant: stages
	bash tools/bench_dac_plant.sh $(BIN) $(OUT)/bench/dac_plant
bench-dac-jumper: stages
	bash tools/bench_dac_jumper.sh $(BIN) $(OUT)/bench/dac_jumper
