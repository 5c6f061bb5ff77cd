# Two-scale topology optimization and its full-resolution check (thesis
# §3.4–3.6, Table 3.1): gamut -> design -> mapping -> homogenized against
# voxel simulation, for four scenes in one 3D cubic gamut of one material
# and void at 16^3 voxels per cell (configs/gamut/cubic3d_bar.yaml, minutes):
#
#   make -f Makefile.pipeline topopt-bar-check       the 8x2x2 bar of Table 3.1 (128x32x32 voxels)
#   make -f Makefile.pipeline topopt-gripper-check   the gripper as a 32x16x2 plate (512x256x32 voxels)
#   make -f Makefile.pipeline topopt-gripper-thesis-check   the gripper at the thesis's 64x32x8 cells
#                                                    (1024x512x128 voxels, design about 10 minutes, each check about 8, 19 GB)
#   make -f Makefile.pipeline topopt-bridge-check    a 24x6x4 bridge (384x96x64 voxels)
#   make -f Makefile.pipeline topopt-cantilever-check a 16x4x8 cantilever (256x64x128 voxels)
#   make -f Makefile.pipeline topopt-checks          all four
#   make -f Makefile.pipeline topopt-bridge-large    the bridge at 128x64x32 cells (Fig. 3-29's grid), optimized
#                                                    with cell MMA: out/topopt/bridge_cubic_large.design.h5 (about 30 min)
#   make -f Makefile.pipeline topopt-bridge-huge     the bridge at 320x160x80 cells (Table 3.2's largest grid) in the
#                                                    lattice family at 64^3, coarse to fine, mapped (1.07e12 voxels; about an hour)
#   make -f Makefile.pipeline topopt-thesis-2d       the thesis's 2D scenes: the S-beam (Fig. 3-18), the four
#                                                    grippers (Fig. 3-20) and the orthotropic lattice (Fig. 3-25)
#   make -f Makefile.pipeline topopt-fig316          Fig. 3-16 on the 2D cantilever: SIMP p = 1 / p = 3, the cubic and
#                                                    orthotropic gamuts of one material + void run to convergence (the
#                                                    orthotropic one seeded with the cubic structures), Ipopt and cell
#                                                    MMA: out/topopt/fig316.md (about 40 minutes, most of it Ipopt)
#   make -f Makefile.pipeline topopt-cubes           Table 3.1's cubes and the tiling study (Fig. 3-23) in
#                                                    configs/gamut/cubic3d_bar_dense.yaml: out/topopt/cubes.md
#                                                    (tools/bench_cubes.sh, about 15 minutes)
#   make -f Makefile.pipeline topopt-bar-tiling      the Table 3.1 bar mapped with 1, 2, 3 copies per cell edge, its twist
#                                                    also as end-face tractions: out/topopt/bar_tiling.md (about 2 minutes)
#
# Per scene S (configs/topopt/S.yaml) it writes out/topopt/S.design.h5,
# S.structures.h5 (the gamut's structures; with FILL_TARGETS=1 plus those
# generated at the design's uncovered targets), S.mapped.h5 (the mapping with its STL surfaces and PNG slice stack for the bar and the
# gripper, the voxel model for all), S.verify.h5, the thesis's comparison
# (one hexahedron per cell), S.h4.verify.h5 (the homogenized model with 4^3
# hexahedra per cell: the homogenization's own error, without most of the
# coarse mesh's stiffness) and S.solid.verify.h5 (every cell solid: the
# coarse mesh's error alone). The bar adds bar.t2.verify.h5 (each cell 2^3
# copies of its structure, 4^3 hexahedra per cell: thinner boundary layers). Each check prints one summary line
# (docs/verify_map.md). SEED (pipelines/gamut.mk) seeds the gamut and the mapping.
# TWO_SCALE_GAMUT names the gamut (configs/gamut/NAME.yaml) the four
# scenes are optimized and mapped in; its results go to out/topopt/NAME/
# (the default's to out/topopt/). graded_lattice is one hand-made family
# whose members connect through every face (configs/families/
# graded_lattice.yaml, docs/mapping.md): it is mapped to the nearest member
# without half-shifted exemplars, which would break the connection.
#   make -f Makefile.pipeline topopt-checks TWO_SCALE_GAMUT=graded_lattice
# TWO_SCALE_FAMILY=NAME designs in a family's own parameters instead of a
# gamut (topopt space family3d, docs/topopt.md): the structure grid of
# configs/families/NAME.yaml is the optimizer's material model and the
# mapping's set; results go to out/topopt/NAME/. These designs are made
# with cell MMA on 4^3 hexahedra per cell (the model the .h4 check uses;
# TOPOPT_ARGS="--set optimizer.name=ipopt --set elements_per_cell=1" for
# the thesis's set-up).
#   make -f Makefile.pipeline topopt-checks TWO_SCALE_FAMILY=graded_lattice_grid
# TOPOPT_ARGS go to msfab-topopt (e.g. "--set gamut_padding=subtract", the
# feasible set ending at the outermost structures), MAP_ARGS to msfab-map
# (e.g. "--set void_pair_cost=0.5 --set starts=16", docs/mapping.md); give
# such a variant its own TOPOPT_DIR.
TWO_SCALE_GAMUT ?= cubic3d_bar
TWO_SCALE_FAMILY ?=
TOPOPT_ARGS ?=
MAP_ARGS ?=
BAR_GAMUT := $(OUT)/gamut/$(TWO_SCALE_GAMUT)
MAP_ARGS_graded_lattice := --set half_shift=false --set candidates=1
MAP_ARGS_cubic3d_bar_backbone := --set half_shift=false
ifneq ($(TWO_SCALE_FAMILY),)
TOPOPT_DIR ?= $(OUT)/topopt/$(TWO_SCALE_FAMILY)
TWO_SCALE_SET := $(OUT)/families/$(TWO_SCALE_FAMILY).microstructures.h5
TWO_SCALE_SPACE := $(TWO_SCALE_SET)
TWO_SCALE_SPACE_ARGS := --set gamut=null --set space=family3d --set family=$(TWO_SCALE_SET) \
  --set optimizer.name=cell-mma --set elements_per_cell=4
TWO_SCALE_MAP_ARGS := --set half_shift=false --set candidates=1
else
ifeq ($(TWO_SCALE_GAMUT),cubic3d_bar)
TOPOPT_DIR ?= $(OUT)/topopt
else
TOPOPT_DIR ?= $(OUT)/topopt/$(TWO_SCALE_GAMUT)
endif
TWO_SCALE_SET := $(BAR_GAMUT).microstructures.h5
TWO_SCALE_SPACE := $(BAR_GAMUT).gamut.h5
TWO_SCALE_SPACE_ARGS := --set gamut=$(BAR_GAMUT).gamut.h5
TWO_SCALE_MAP_ARGS := $(MAP_ARGS_$(TWO_SCALE_GAMUT))
endif
CUBES_GAMUT := $(OUT)/gamut/cubic3d_bar_dense
TWO_SCALE_SCENES := bar gripper3d bridge_cubic cantilever_cubic
# Scenes built by the same rules but not part of topopt-checks (each check
# of the thesis-resolution gripper solves 67 M voxels: about 8 minutes on 2 cores).
TWO_SCALE_LARGE_SCENES := gripper3d_thesis
TWO_SCALE_ALL := $(TWO_SCALE_SCENES) $(TWO_SCALE_LARGE_SCENES)

$(OUT)/gamut/graded_lattice.gamut.h5: $(OUT)/families/graded_lattice.microstructures.h5
HAND_MADE_FAMILIES := graded_lattice graded_lattice_grid
$(HAND_MADE_FAMILIES:%=$(OUT)/families/%.microstructures.h5): $(OUT)/families/%.microstructures.h5: \
    configs/families/%.yaml $(STAGE_ID)/msfab-family-generate.id
	@mkdir -p $(@D)
	$(BIN)/msfab-family-generate --config $< --threads $(THREADS) --out $@ $(QUIET)

# msfab-gamut-sample writes both artifacts in one commit, the set first, so
# the set can be older than its gamut by the time the gamut took to write;
# its time is set to the gamut's, or make would rerun everything below it
# on every call.
$(BAR_GAMUT).microstructures.h5: $(BAR_GAMUT).gamut.h5
	@test -s $@ && touch -r $< $@

$(TWO_SCALE_ALL:%=$(TOPOPT_DIR)/%.design.h5): $(TOPOPT_DIR)/%.design.h5: configs/topopt/%.yaml \
    $(TWO_SCALE_SPACE) $(STAGE_ID)/msfab-topopt.id
	@mkdir -p $(@D)
	$(BIN)/msfab-topopt --config $< $(TWO_SCALE_SPACE_ARGS) $(TOPOPT_ARGS) --threads $(THREADS) --out $@ $(QUIET)

# The gamut's structures, with FILL_TARGETS=1 plus structures generated at
# the design's targets that the gamut does not cover (msfab-fill-targets). The targets fan out over MPI ranks with
# FILL_MPIRUN="$(MPIRUN)" (RANKS, pipelines/ddfem.mk) or "srun" on a cluster.
# Off by default. What helped the bridge (docs/BENCHMARKS.md, "Structures
# at the targets and face connectors"):
#   make -f Makefile.pipeline topopt-bridge-check FILL_TARGETS=1 MATCH=stiffness \
#     FILL_ARGS="--set connector.half_width=3 --set refine.density_weight=0.1"
# The same settings leave the gripper plate's loaded jaw as a piece its
# supports do not hold, and its check refuses to run.
FILL_TARGETS ?= 0
FILL_MPIRUN ?=
MATCH ?= all
FILL_ARGS ?=
$(TWO_SCALE_ALL:%=$(TOPOPT_DIR)/%.structures.h5): $(TOPOPT_DIR)/%.structures.h5: $(TOPOPT_DIR)/%.design.h5 \
    $(TWO_SCALE_SET) $(STAGE_ID)/msfab-fill-targets.id
ifeq ($(FILL_TARGETS),0)
	cp $(TWO_SCALE_SET) $@.tmp && mv $@.tmp $@
else
	OMP_NUM_THREADS=$(THREADS) $(FILL_MPIRUN) $(BIN)/msfab-fill-targets --design $< --structures $(TWO_SCALE_SET) \
	  --set match=$(MATCH) $(FILL_ARGS) --threads $(THREADS) --out $@
endif

# Exports: the voxel model always; STL surfaces and a PNG slice per voxel
# layer for the smaller models.
MAP_EXPORTS_bar := --set export.stl=true --set export.png=true
MAP_EXPORTS_gripper3d := --set export.stl=true --set export.png=true
MAP_EXPORTS_gripper3d_thesis := --set export.png=true
$(TWO_SCALE_ALL:%=$(TOPOPT_DIR)/%.mapped.h5): $(TOPOPT_DIR)/%.mapped.h5: $(TOPOPT_DIR)/%.design.h5 \
    $(TOPOPT_DIR)/%.structures.h5 $(STAGE_ID)/msfab-map.id
	$(BIN)/msfab-map --design $< --structures $(TOPOPT_DIR)/$*.structures.h5 --seed $(SEED) --set match=$(MATCH) \
	  --set export.voxels=true $(MAP_EXPORTS_$*) $(TWO_SCALE_MAP_ARGS) $(MAP_ARGS) --threads $(THREADS) --out $@ $(QUIET)

# The three checks of Table 3.1 per scene: S.verify.h5 (one hexahedron per
# cell), S.h4.verify.h5 and S.solid.verify.h5, differing only in settings.
VERIFY_SETTINGS_ :=
VERIFY_SETTINGS_.h4 := --set homogenized_elements=4
VERIFY_SETTINGS_.solid := --set fill=solid
define TWO_SCALE_CHECK
$(TWO_SCALE_ALL:%=$(TOPOPT_DIR)/%$(1).verify.h5): $(TOPOPT_DIR)/%$(1).verify.h5: $(TOPOPT_DIR)/%.mapped.h5 \
    $(TOPOPT_DIR)/%.design.h5 $(STAGE_ID)/msfab-verify-map.id
	$(BIN)/msfab-verify-map --design $(TOPOPT_DIR)/$$*.design.h5 --mapped $$< \
	  --structures $(TOPOPT_DIR)/$$*.structures.h5 $(VERIFY_SETTINGS_$(1)) --threads $(THREADS) --out $$@
endef
$(foreach variant,_ .h4 .solid,$(eval $(call TWO_SCALE_CHECK,$(variant:_=))))

$(TOPOPT_DIR)/bar.t2.mapped.h5: $(TOPOPT_DIR)/bar.design.h5 $(TOPOPT_DIR)/bar.structures.h5 $(STAGE_ID)/msfab-map.id
	$(BIN)/msfab-map --design $< --structures $(TOPOPT_DIR)/bar.structures.h5 --seed $(SEED) --set match=$(MATCH) --set tiling=2 \
	  $(TWO_SCALE_MAP_ARGS) $(MAP_ARGS) --threads $(THREADS) --out $@ $(QUIET)

$(TOPOPT_DIR)/bar.t2.verify.h5: $(TOPOPT_DIR)/bar.t2.mapped.h5 $(TOPOPT_DIR)/bar.design.h5 $(STAGE_ID)/msfab-verify-map.id
	$(BIN)/msfab-verify-map --design $(TOPOPT_DIR)/bar.design.h5 --mapped $< \
	  --structures $(TOPOPT_DIR)/bar.structures.h5 --set homogenized_elements=4 --threads $(THREADS) --out $@

# The bar against tiling (t = 1, 2, 3 copies per cell edge) under its loads
# and the twist as end-face tractions (configs/topopt/bar_check_loads.yaml):
# docs/BENCHMARKS.md, "The bar's twist against tiling"; about 2 minutes.
$(OUT)/topopt/bar_tiling.md: $(TOPOPT_DIR)/bar.design.h5 $(TOPOPT_DIR)/bar.structures.h5 tools/bench_bar_tiling.sh \
    configs/topopt/bar_check_loads.yaml $(STAGE_ID)/msfab-map.id $(STAGE_ID)/msfab-verify-map.id
	bash tools/bench_bar_tiling.sh $(BIN) $(OUT)/topopt/bar_tiling $(TOPOPT_DIR)/bar.design.h5 \
	  $(TOPOPT_DIR)/bar.structures.h5 $(SEED) > $@.tmp && mv $@.tmp $@ && cat $@

$(CUBES_GAMUT).microstructures.h5: $(CUBES_GAMUT).gamut.h5
	@test -s $@ && touch -r $< $@

$(OUT)/topopt/cubes.md: $(CUBES_GAMUT).microstructures.h5 tools/bench_cubes.sh configs/assign/cube.yaml \
    $(STAGE_ID)/msfab-assign.id $(STAGE_ID)/msfab-map.id $(STAGE_ID)/msfab-verify-map.id
	@mkdir -p $(@D)
	bash tools/bench_cubes.sh $(BIN) $(OUT)/topopt/cubes $(CUBES_GAMUT).microstructures.h5 > $@.tmp
	mv $@.tmp $@
	@cat $@

# The bridge at the thesis's optimization grid: optimization only (its
# 254k cells are 537 M voxels at 16^3, beyond a full-resolution check here).
$(OUT)/topopt/bridge_cubic_large.design.h5: configs/topopt/bridge_cubic_large.yaml $(BAR_GAMUT).gamut.h5 $(STAGE_ID)/msfab-topopt.id
	@mkdir -p $(@D)
	$(BIN)/msfab-topopt --config $< --set gamut=$(BAR_GAMUT).gamut.h5 --threads $(THREADS) --out $@

# The bridge at Table 3.2's largest grid, end to end: 320x160x80 cells
# designed in the connected lattice family generated at 64^3 voxels per
# cell (1.07e12 voxels), coarse to fine (80x40x20, 160x80x40, then
# HUGE_ITERATIONS cell MMA steps at 320x160x80), and mapped cell by cell
# onto the family's members (the mapped artifact names each cell's member;
# the voxels are not written). 16 GB of memory at the finest grid, about an
# hour on 2 cores (docs/BENCHMARKS.md, "The bridge at 320x160x80").
HUGE_DIR := $(OUT)/topopt/huge
HUGE_FAMILY := $(OUT)/families/graded_lattice_grid64.microstructures.h5
HUGE_ITERATIONS ?= 4
HUGE_CONFIG := configs/topopt/bridge_family_huge.yaml
HUGE_TOPOPT = $(BIN)/msfab-topopt --config $(HUGE_CONFIG) --set family=$(HUGE_FAMILY) --threads $(THREADS)
$(HUGE_FAMILY): configs/families/graded_lattice_grid.yaml $(STAGE_ID)/msfab-family-generate.id
	@mkdir -p $(@D)
	$(BIN)/msfab-family-generate --config $< --set resolution=64 --threads $(THREADS) --out $@ $(QUIET)
$(HUGE_DIR)/bridge80.design.h5: $(HUGE_CONFIG) $(HUGE_FAMILY) $(STAGE_ID)/msfab-topopt.id
	@mkdir -p $(@D)
	$(HUGE_TOPOPT) --set grid="{size: [80, 40, 20], cell_size: 4.0}" --set optimizer.max_iterations=30 \
	  --set domain="[{box: {min: [0, 0, 76], max: [320, 160, 80]}, role: solid}]" --out $@
$(HUGE_DIR)/bridge160.design.h5: $(HUGE_DIR)/bridge80.design.h5
	$(HUGE_TOPOPT) --set grid="{size: [160, 80, 40], cell_size: 2.0}" --set optimizer.max_iterations=40 \
	  --set domain="[{box: {min: [0, 0, 78], max: [320, 160, 80]}, role: solid}]" --set initial="{design: $<}" --out $@
$(HUGE_DIR)/bridge320.design.h5: $(HUGE_DIR)/bridge160.design.h5
	$(HUGE_TOPOPT) --set optimizer.max_iterations=$(HUGE_ITERATIONS) --set initial="{design: $<}" --out $@
$(HUGE_DIR)/bridge320.mapped.h5: $(HUGE_DIR)/bridge320.design.h5 $(HUGE_FAMILY) $(STAGE_ID)/msfab-map.id
	$(BIN)/msfab-map --design $< --structures $(HUGE_FAMILY) --set half_shift=false --set candidates=1 \
	  --seed $(SEED) --threads $(THREADS) --out $@

# The thesis's 2D scenes, each in its gamut.
THESIS_2D_SCENES := s_beam orthotropic_lattice gripper gripper_pull gripper_push gripper_stretch
GAMUT_s_beam := cubic2d
GAMUT_orthotropic_lattice := orthotropic2d
GAMUT_gripper := cubic2d_void
GAMUT_gripper_pull := cubic2d_void
GAMUT_gripper_push := cubic2d_void
GAMUT_gripper_stretch := cubic2d_void
define THESIS_2D_DESIGN
$(OUT)/topopt/$(1).design.h5: configs/topopt/$(1).yaml $(OUT)/gamut/$(2).gamut.h5 $(STAGE_ID)/msfab-topopt.id
	@mkdir -p $$(@D)
	$(BIN)/msfab-topopt --config $$< --set gamut=$(OUT)/gamut/$(2).gamut.h5 --threads $(THREADS) --out $$@
endef
$(foreach s,$(THESIS_2D_SCENES),$(eval $(call THESIS_2D_DESIGN,$(s),$(GAMUT_$(s)))))

# The orthotropic gamut of Fig. 3-16 starts from the cubic gamut's
# structures (every cubic material is orthotropic), then runs to convergence.
FIG316_CUBIC := $(OUT)/gamut/converged/cubic2d_void
FIG316_ORTHO := $(OUT)/gamut/converged/orthotropic2d_void_seeded
$(FIG316_ORTHO).gamut.h5: configs/gamut/orthotropic2d_void.yaml $(FIG316_CUBIC).gamut.h5 $(STAGE_ID)/msfab-gamut-sample.id
	@mkdir -p $(@D)
	OMP_NUM_THREADS=$(THREADS) $(MPIRUN) $(BIN)/msfab-gamut-sample --config $< --seed $(SEED) --out $@ --resume \
	  --set cycles=$(CONVERGE_CYCLES) --set plot_every_cycle=false \
	  --set stop='{coverage_growth: $(CONVERGE_GROWTH), window: $(CONVERGE_WINDOW)}' \
	  --set initial_set='{path: $(abspath $(FIG316_CUBIC)).microstructures.h5}'
$(OUT)/topopt/fig316.md: $(FIG316_CUBIC).gamut.h5 $(FIG316_ORTHO).gamut.h5 tools/bench_topopt.sh $(STAGE_ID)/msfab-topopt.id
	@mkdir -p $(@D)
	CANTILEVER_ONLY=1 CUBIC2D=$(FIG316_CUBIC).gamut.h5 ORTHO2D=$(FIG316_ORTHO).gamut.h5 \
	  bash tools/bench_topopt.sh $(BUILD) > $@.tmp
	mv $@.tmp $@

.PHONY: topopt-fig316
topopt-fig316: stages $(OUT)/topopt/fig316.md

.PHONY: topopt-thesis-2d
topopt-thesis-2d: stages $(THESIS_2D_SCENES:%=$(OUT)/topopt/%.design.h5)

.PHONY: topopt-bar-tiling topopt-bar-check topopt-gripper-check topopt-bridge-check topopt-cantilever-check topopt-checks topopt-cubes \
    topopt-bridge-large topopt-bridge-huge topopt-gripper-thesis-check
topopt-bar-check: stages $(TOPOPT_DIR)/bar.verify.h5 $(TOPOPT_DIR)/bar.h4.verify.h5 $(TOPOPT_DIR)/bar.solid.verify.h5 \
    $(TOPOPT_DIR)/bar.t2.verify.h5
topopt-cubes: stages $(OUT)/topopt/cubes.md
topopt-bar-tiling: stages $(OUT)/topopt/bar_tiling.md
topopt-gripper-check: stages $(TOPOPT_DIR)/gripper3d.verify.h5 $(TOPOPT_DIR)/gripper3d.h4.verify.h5 \
    $(TOPOPT_DIR)/gripper3d.solid.verify.h5
topopt-bridge-check: stages $(TOPOPT_DIR)/bridge_cubic.verify.h5 $(TOPOPT_DIR)/bridge_cubic.h4.verify.h5 \
    $(TOPOPT_DIR)/bridge_cubic.solid.verify.h5
topopt-cantilever-check: stages $(TOPOPT_DIR)/cantilever_cubic.verify.h5 $(TOPOPT_DIR)/cantilever_cubic.h4.verify.h5 \
    $(TOPOPT_DIR)/cantilever_cubic.solid.verify.h5
topopt-checks: topopt-bar-check topopt-gripper-check topopt-bridge-check topopt-cantilever-check
# The gripper at the thesis's 64x32x8 cells (configs/topopt/gripper3d_thesis.yaml),
# checked against its homogenized model with 4^3 hexahedra per cell: about
# 10 minutes of cell MMA and 34 minutes for the 67 M-voxel check on 2 cores
# (peak 20 GB; docs/BENCHMARKS.md, "The gripper at the thesis's resolution").
topopt-gripper-thesis-check: stages $(TOPOPT_DIR)/gripper3d_thesis.h4.verify.h5
topopt-bridge-large: stages $(OUT)/topopt/bridge_cubic_large.design.h5
topopt-bridge-huge: stages $(HUGE_DIR)/bridge320.mapped.h5
