# DDFEM (thesis ch. 2): coarse-material databases and the Table 2.2 benchmark.
#
#   make -f Makefile.pipeline ddfem-db-tiny      2 materials, seconds (demo, tests)
#   make -f Makefile.pipeline ddfem-db-level1    3 materials (Table 2.2 palette), minutes; MPI fan-out
#   make -f Makefile.pipeline ddfem-db-level2    level 2 over level 1 compressed to 400 materials, minutes
#   make -f Makefile.pipeline ddfem-table        regenerate the Table 2.2 analogue in docs/BENCHMARKS.md
#   make -f Makefile.pipeline ddfem-table-periodic  the same with in-situ (periodic) sampling, its own section
#   make -f Makefile.pipeline ddfem-table-centre    periodic sampling and a fitted centre point, its own section
#   make -f Makefile.pipeline ddfem-table-void      periodic sampling with void in the palette, its own section
#   make -f Makefile.pipeline ddfem-table-adaptive  adaptive coarsening (--target-error): speed against error, PNG
#   make -f Makefile.pipeline ddfem-table-adaptive-enhanced  the same on the enhanced element, Galerkin fallback
#   make -f Makefile.pipeline ddfem-table-floor     error floor of the coarse meshes, homogenized reference, its own section
#   make -f Makefile.pipeline ddfem-table-enhanced  level 1 fitted for the enhanced coarse element, its own section
#   make -f Makefile.pipeline ddfem-table-mixed     mixed blocks: naive, Galerkin and DDFEM on both elements, its own section
#   make -f Makefile.pipeline ddfem-table-level2-variants  level 2 sampled on fine voxels, and with corner moves in the lookup
#   make -f Makefile.pipeline ddfem-table-checked   matched coarsening, and DDFEM lookups checked against each block's own C^H
#   make -f Makefile.pipeline ddfem-table-adaptive-checked  adaptive coarsening with the checked lookup
#   make -f Makefile.pipeline ddfem-table-adaptive-level1db  the same, level-1 cells from the full level-1 database
#   make -f Makefile.pipeline ddfem-table-adaptive-posterior  the same with the a-posteriori check (--posterior-check)
#   make -f Makefile.pipeline ddfem-table-adaptive-newton     the same, estimated by one fine Newton step (--posterior-estimate newton)
#   make -f Makefile.pipeline ddfem-table-adaptive-fibers     the fibre bar (330 k unknowns) adaptively, Newton estimate
#   make -f Makefile.pipeline ddfem-table-current     Table 2.2 with today's DDFEM model (enhanced affine databases, checked lookup)
#   make -f Makefile.pipeline ddfem-table-windowed  matched materials carried onto each cell's stiffness among its real neighbours
#   make -f Makefile.pipeline ddfem-table-window-checked  DDFEM lookups checked against each cell's stiffness among its real neighbours
#   make -f Makefile.pipeline ddfem-table-dynamics  DDFEM in dynamics: the fibre bar fine, level 1 and 2, trajectory error and speed
#   make -f Makefile.pipeline ddfem-table-thesis-settings  the thesis's sampling and fit, and level 2 over 100/400/1024 materials
#
# RANKS=<n> runs the builder on n MPI ranks (THREADS threads each); on a
# cluster MPIRUN="srun" (pipelines/slurm/ddfem_build.sbatch). A build that is
# interrupted resumes from its checkpoint when the target is made again.
RANKS  ?= 1
# --bind-to none: Open MPI pins each of up to 2 ranks to one core, so a
# single rank's THREADS OpenMP threads would share that core (measured: half
# the orbits per second of the same build without mpirun).
MPIRUN ?= mpirun --oversubscribe --bind-to none -np $(RANKS)

$(OUT)/ddfem/%.coarse_db.h5: configs/ddfem/%.yaml $(STAGE_ID)/msfab-ddfem-build.id
	@mkdir -p $(@D)
	OMP_NUM_THREADS=$(THREADS) $(MPIRUN) $(BIN)/msfab-ddfem-build --config $< --out $@ --resume

# Level 2 (§2.3.5): <name>_level2.yaml over <name>'s level-1 database
# compressed to K1 materials.
K1 ?= 400
# Kept: the compressed level-1 database is an input others reuse (make would
# delete it as an intermediate of the level-2 build).
.PRECIOUS: $(OUT)/ddfem/%.k$(K1).coarse_db.h5
$(OUT)/ddfem/%.k$(K1).coarse_db.h5: $(OUT)/ddfem/%.coarse_db.h5 $(STAGE_ID)/msfab-ddfem-compress.id
	$(BIN)/msfab-ddfem-compress --database $< --set representatives=$(K1) --out $@
$(OUT)/ddfem/%.level2.coarse_db.h5: configs/ddfem/%_level2.yaml $(OUT)/ddfem/%.k$(K1).coarse_db.h5 $(STAGE_ID)/msfab-ddfem-build.id
	@mkdir -p $(@D)
	OMP_NUM_THREADS=$(THREADS) $(MPIRUN) $(BIN)/msfab-ddfem-build --config $< \
	  --set base_database=$(OUT)/ddfem/$*.k$(K1).coarse_db.h5 --out $@ --resume

.PHONY: ddfem-db-tiny ddfem-db-level1 ddfem-db-level2 ddfem-table ddfem-table-periodic ddfem-table-centre ddfem-table-void \
        ddfem-table-adaptive ddfem-table-adaptive-enhanced ddfem-table-floor ddfem-table-enhanced ddfem-table-mixed ddfem-table-level2-variants ddfem-table-checked ddfem-table-adaptive-checked ddfem-table-adaptive-level1db ddfem-table-adaptive-posterior ddfem-table-adaptive-newton ddfem-table-adaptive-fibers ddfem-table-current ddfem-table-windowed ddfem-table-window-checked \
        ddfem-table-dynamics
ddfem-db-tiny: stages $(OUT)/ddfem/tiny.coarse_db.h5
ddfem-db-level1: stages $(OUT)/ddfem/palette3.coarse_db.h5
ddfem-db-level2: stages $(OUT)/ddfem/palette3.level2.coarse_db.h5

ddfem-table: stages $(OUT)/ddfem/palette3.coarse_db.h5 $(OUT)/ddfem/palette3.level2.coarse_db.h5
	DATABASE2=$(OUT)/ddfem/palette3.level2.coarse_db.h5 \
	  bash tools/bench_ddfem.sh $(BIN) $(OUT)/bench/ddfem docs/BENCHMARKS.md $(OUT)/ddfem/palette3.coarse_db.h5

# In-situ sampling (docs/ddfem.md): both levels sampled periodically.
ddfem-table-periodic: stages $(OUT)/ddfem/palette3_periodic.coarse_db.h5 $(OUT)/ddfem/palette3_periodic.level2.coarse_db.h5
	BENCH_SECTION=ddfem-periodic DATABASE2=$(OUT)/ddfem/palette3_periodic.level2.coarse_db.h5 \
	  bash tools/bench_ddfem.sh $(BIN) $(OUT)/bench/ddfem-periodic docs/BENCHMARKS.md \
	  $(OUT)/ddfem/palette3_periodic.coarse_db.h5

# The centre point (docs/ddfem.md, "Centre point") on periodic databases.
ddfem-table-centre: stages $(OUT)/ddfem/palette3_periodic_centre.coarse_db.h5 \
                    $(OUT)/ddfem/palette3_periodic_centre.level2.coarse_db.h5
	BENCH_SECTION=ddfem-centre DATABASE2=$(OUT)/ddfem/palette3_periodic_centre.level2.coarse_db.h5 \
	  bash tools/bench_ddfem.sh $(BIN) $(OUT)/bench/ddfem-centre docs/BENCHMARKS.md \
	  $(OUT)/ddfem/palette3_periodic_centre.coarse_db.h5

# What limits coarsening (docs/ddfem.md, "Error floor and the homogenized
# reference"): every scene at both levels, naive, homogenized and DDFEM
# against the floor no coarse model can beat.
ddfem-table-floor: stages $(OUT)/ddfem/palette3_periodic_centre.coarse_db.h5 \
                   $(OUT)/ddfem/palette3_periodic_centre.level2.coarse_db.h5
	bash tools/bench_ddfem_floor.sh $(BIN) $(OUT)/bench/ddfem-floor docs/BENCHMARKS.md \
	  $(OUT)/ddfem/palette3_periodic_centre.coarse_db.h5 $(OUT)/ddfem/palette3_periodic_centre.level2.coarse_db.h5

# The fit on the enhanced coarse element (docs/ddfem.md, "Fit on the
# enhanced element"): level 1, the same columns as ddfem-table-floor.
ddfem-table-enhanced: stages $(OUT)/ddfem/palette3_periodic_enhanced.coarse_db.h5
	LEVELS=1 BENCH_SECTION=ddfem-enhanced bash tools/bench_ddfem_floor.sh $(BIN) $(OUT)/bench/ddfem-enhanced \
	  docs/BENCHMARKS.md $(OUT)/ddfem/palette3_periodic_enhanced.coarse_db.h5 -

# Mixed blocks (docs/ddfem.md, "Galerkin element", "Affine samples on
# the enhanced element"): naive and Galerkin coarsening on both elements at both levels,
# DDFEM of the enhanced databases fitted on affine samples (both levels),
# its blocks without a fit naive or Galerkin.
ddfem-table-mixed: stages $(OUT)/ddfem/palette3_periodic_enhanced_affine.coarse_db.h5 \
                   $(OUT)/ddfem/palette3_periodic_enhanced_affine.level2.coarse_db.h5
	bash tools/bench_ddfem_mixed.sh $(BIN) $(OUT)/bench/ddfem-mixed docs/BENCHMARKS.md \
	  $(OUT)/ddfem/palette3_periodic_enhanced_affine.coarse_db.h5 $(OUT)/ddfem/palette3_periodic_enhanced_affine.level2.coarse_db.h5

# Level-2 variants of the mixed table's database (docs/ddfem.md, "Level 2"),
# blocks without a fit by the Galerkin element: each final block sampled on
# its 4 x 4 x 4 voxels instead of its 2 x 2 x 2 level-1 elements; and the
# lookup's features with the single-corner moves, at the level-1
# compression (k$(K1)c) and at every pairing stage.
.PRECIOUS: $(OUT)/ddfem/%.k$(K1)c.coarse_db.h5
$(OUT)/ddfem/%.k$(K1)c.coarse_db.h5: $(OUT)/ddfem/%.coarse_db.h5 $(STAGE_ID)/msfab-ddfem-compress.id
	$(BIN)/msfab-ddfem-compress --database $< --set representatives=$(K1) --set corner_moves=true --out $@
AFFINE_CORNER_L2 := $(foreach v,corners corners800,$(OUT)/ddfem/palette3_periodic_enhanced_affine_$(v).level2.coarse_db.h5)
$(AFFINE_CORNER_L2): $(OUT)/ddfem/palette3_periodic_enhanced_affine_%.level2.coarse_db.h5: \
  configs/ddfem/palette3_periodic_enhanced_affine_%_level2.yaml \
  $(OUT)/ddfem/palette3_periodic_enhanced_affine.k$(K1)c.coarse_db.h5 $(STAGE_ID)/msfab-ddfem-build.id
	@mkdir -p $(@D)
	OMP_NUM_THREADS=$(THREADS) $(MPIRUN) $(BIN)/msfab-ddfem-build --config $< \
	  --set base_database=$(OUT)/ddfem/palette3_periodic_enhanced_affine.k$(K1)c.coarse_db.h5 --out $@ --resume
$(OUT)/ddfem/palette3_periodic_enhanced_affine_voxels.level2.coarse_db.h5: \
  configs/ddfem/palette3_periodic_enhanced_affine_voxels_level2.yaml \
  $(OUT)/ddfem/palette3_periodic_enhanced_affine.k$(K1).coarse_db.h5 $(STAGE_ID)/msfab-ddfem-build.id
	@mkdir -p $(@D)
	OMP_NUM_THREADS=$(THREADS) $(MPIRUN) $(BIN)/msfab-ddfem-build --config $< \
	  --set base_database=$(OUT)/ddfem/palette3_periodic_enhanced_affine.k$(K1).coarse_db.h5 --out $@ --resume
ddfem-table-level2-variants: stages $(OUT)/ddfem/palette3_periodic_enhanced_affine.level2.coarse_db.h5 \
                             $(OUT)/ddfem/palette3_periodic_enhanced_affine_voxels.level2.coarse_db.h5 \
                             $(OUT)/ddfem/palette3_periodic_enhanced_affine_corners.level2.coarse_db.h5 \
                             $(OUT)/ddfem/palette3_periodic_enhanced_affine_corners800.level2.coarse_db.h5
	LEVEL=2 COARSE_ARGS="--coarse-fallback galerkin" BENCH_SECTION=ddfem-level2-variants \
	  bash tools/bench_ddfem_databases.sh $(BIN) $(OUT)/bench/ddfem-level2-variants docs/BENCHMARKS.md \
	  level1-elements=$(OUT)/ddfem/palette3_periodic_enhanced_affine.level2.coarse_db.h5 \
	  fine-voxels=$(OUT)/ddfem/palette3_periodic_enhanced_affine_voxels.level2.coarse_db.h5 \
	  corner-lookup=$(OUT)/ddfem/palette3_periodic_enhanced_affine_corners.level2.coarse_db.h5 \
	  corner-lookup-800=$(OUT)/ddfem/palette3_periodic_enhanced_affine_corners800.level2.coarse_db.h5

# Matched coarsening and the checked lookup (docs/ddfem.md, "Matched
# materials and the checked lookup"): both levels on the references of the
# level-2 variants; CHECK is the --coarse-check tolerance.
CHECK ?= 0.1
ENHANCED_NAIVE := --coarse-material naive --coarse-element enhanced
ddfem-table-checked: stages $(OUT)/ddfem/palette3_periodic_enhanced_affine.coarse_db.h5 \
                     $(OUT)/ddfem/palette3_periodic_enhanced_affine.k$(K1).coarse_db.h5 \
                     $(OUT)/ddfem/palette3_periodic_enhanced_affine.k$(K1)c.coarse_db.h5 \
                     $(OUT)/ddfem/palette3_periodic_enhanced_affine.level2.coarse_db.h5 \
                     $(OUT)/ddfem/palette3_periodic_enhanced_affine_corners.level2.coarse_db.h5
	LEVEL=2 BENCH_SECTION=ddfem-checked-level2 \
	  bash tools/bench_ddfem_databases.sh $(BIN) $(OUT)/bench/ddfem-level2-variants docs/BENCHMARKS.md \
	  naive-enhanced="$(ENHANCED_NAIVE)" matched="--coarse-material matched --coarse-element enhanced" \
	  ddfem="--database $(OUT)/ddfem/palette3_periodic_enhanced_affine.level2.coarse_db.h5 --coarse-fallback galerkin" \
	  ddfem-checked="--database $(OUT)/ddfem/palette3_periodic_enhanced_affine.level2.coarse_db.h5 --coarse-fallback galerkin --coarse-check $(CHECK)" \
	  corner-lookup="--database $(OUT)/ddfem/palette3_periodic_enhanced_affine_corners.level2.coarse_db.h5 --coarse-fallback galerkin" \
	  corner-lookup-checked="--database $(OUT)/ddfem/palette3_periodic_enhanced_affine_corners.level2.coarse_db.h5 --coarse-fallback galerkin --coarse-check $(CHECK)"
	LEVEL=1 BENCH_SECTION=ddfem-checked-level1 \
	  bash tools/bench_ddfem_databases.sh $(BIN) $(OUT)/bench/ddfem-level2-variants docs/BENCHMARKS.md \
	  naive-enhanced="$(ENHANCED_NAIVE)" \
	  full="--database $(OUT)/ddfem/palette3_periodic_enhanced_affine.coarse_db.h5 --coarse-fallback galerkin" \
	  full-checked="--database $(OUT)/ddfem/palette3_periodic_enhanced_affine.coarse_db.h5 --coarse-fallback galerkin --coarse-check $(CHECK)" \
	  k$(K1)="--database $(OUT)/ddfem/palette3_periodic_enhanced_affine.k$(K1).coarse_db.h5 --coarse-fallback galerkin" \
	  k$(K1)-checked="--database $(OUT)/ddfem/palette3_periodic_enhanced_affine.k$(K1).coarse_db.h5 --coarse-fallback galerkin --coarse-check $(CHECK)" \
	  k$(K1)c="--database $(OUT)/ddfem/palette3_periodic_enhanced_affine.k$(K1)c.coarse_db.h5 --coarse-fallback galerkin" \
	  k$(K1)c-checked="--database $(OUT)/ddfem/palette3_periodic_enhanced_affine.k$(K1)c.coarse_db.h5 --coarse-fallback galerkin --coarse-check $(CHECK)"

# DDFEM in dynamics (docs/ddfem.md, "Coarsening in dynamics"): the fibre bar
# fine and at both levels, naive and the isolated and periodic databases.
ddfem-table-dynamics: stages $(OUT)/ddfem/palette3.coarse_db.h5 $(OUT)/ddfem/palette3.level2.coarse_db.h5 \
                      $(OUT)/ddfem/palette3_periodic.coarse_db.h5 $(OUT)/ddfem/palette3_periodic.level2.coarse_db.h5
	bash tools/bench_ddfem_dynamics.sh $(BIN) $(OUT)/bench/ddfem-dynamics \
	  L1:isolated=$(OUT)/ddfem/palette3.coarse_db.h5 L1:periodic=$(OUT)/ddfem/palette3_periodic.coarse_db.h5 \
	  L2:isolated=$(OUT)/ddfem/palette3.level2.coarse_db.h5 L2:periodic=$(OUT)/ddfem/palette3_periodic.level2.coarse_db.h5

# Void in the palette (docs/ddfem.md, "Blocks with void"): blocks with void
# children fitted, periodic sampling at both levels.
ddfem-table-void: stages $(OUT)/ddfem/palette3_periodic_void.coarse_db.h5 \
                  $(OUT)/ddfem/palette3_periodic_void.level2.coarse_db.h5
	BENCH_SECTION=ddfem-void DATABASE2=$(OUT)/ddfem/palette3_periodic_void.level2.coarse_db.h5 \
	  bash tools/bench_ddfem.sh $(BIN) $(OUT)/bench/ddfem-void docs/BENCHMARKS.md \
	  $(OUT)/ddfem/palette3_periodic_void.coarse_db.h5

# Adaptive coarsening (docs/ddfem.md, "Adaptive coarsening") over the
# periodic level-2 database; TARGETS="..." picks the target errors.
ddfem-table-adaptive: stages $(OUT)/ddfem/palette3_periodic.coarse_db.h5 $(OUT)/ddfem/palette3_periodic.level2.coarse_db.h5
	DATABASE1=$(OUT)/ddfem/palette3_periodic.coarse_db.h5 \
	  bash tools/bench_adaptive.sh $(BIN) $(OUT)/bench/ddfem-adaptive docs/BENCHMARKS.md \
	  $(OUT)/ddfem/palette3_periodic.level2.coarse_db.h5

# The same on the enhanced element (docs/ddfem.md, "Adaptive coarsening"):
# the affine databases of ddfem-table-mixed (ENHANCED_DB), blocks without a
# fit by the Galerkin element (FALLBACK=naive for the naive fallback);
# ENHANCED_DB=palette3_periodic_enhanced_affine_void fits the blocks with
# void too (its level 2 takes hours; docs/BENCHMARKS.md).
FALLBACK ?= galerkin
ENHANCED_DB ?= palette3_periodic_enhanced_affine
ddfem-table-adaptive-enhanced: stages $(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 $(OUT)/ddfem/$(ENHANCED_DB).level2.coarse_db.h5
	DATABASE1=$(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 BENCH_SECTION=ddfem-adaptive-enhanced \
	  COARSE_ARGS="--coarse-fallback $(FALLBACK)" \
	  bash tools/bench_adaptive.sh $(BIN) $(OUT)/bench/ddfem-adaptive-$(ENHANCED_DB)-$(FALLBACK) docs/BENCHMARKS.md \
	  $(OUT)/ddfem/$(ENHANCED_DB).level2.coarse_db.h5

# Windowed matched materials (docs/ddfem.md, "Windowed stiffness"): each
# cell carried onto its stiffness among WINDOW voxels of its real
# neighbours, beside matched and naive materials on the same element.
WINDOW ?= 2
ddfem-table-windowed: stages
	for level in 2 1; do \
	  LEVEL=$$level BENCH_SECTION=ddfem-windowed-level$$level \
	  bash tools/bench_ddfem_databases.sh $(BIN) $(OUT)/bench/ddfem-level2-variants docs/BENCHMARKS.md \
	    naive-enhanced="$(ENHANCED_NAIVE)" matched="--coarse-material matched --coarse-element enhanced" \
	    matched-window="--coarse-material matched --coarse-element enhanced --coarse-window $(WINDOW)" || exit 1; \
	done

# The lookup checked against each cell's windowed stiffness instead of its
# periodic C^H (--coarse-check $(CHECK) --coarse-window $(WINDOW)), both levels.
ddfem-table-window-checked: stages $(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 $(OUT)/ddfem/$(ENHANCED_DB).level2.coarse_db.h5
	for level in 2 1; do \
	  db=$(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5; [ $$level = 1 ] || db=$(OUT)/ddfem/$(ENHANCED_DB).level2.coarse_db.h5; \
	  LEVEL=$$level BENCH_SECTION=ddfem-window-checked-level$$level \
	  bash tools/bench_ddfem_databases.sh $(BIN) $(OUT)/bench/ddfem-window-checked docs/BENCHMARKS.md \
	    naive-enhanced="$(ENHANCED_NAIVE)" \
	    checked="--database $$db --coarse-fallback galerkin --coarse-check $(CHECK)" \
	    window-checked="--database $$db --coarse-fallback galerkin --coarse-check $(CHECK) --coarse-window $(WINDOW)" \
	    matched-window="--coarse-material matched --coarse-element enhanced --coarse-window $(WINDOW)" || exit 1; \
	done

# The same with the checked lookup (--coarse-check $(CHECK)) at both levels.
ddfem-table-adaptive-checked: stages $(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 $(OUT)/ddfem/$(ENHANCED_DB).level2.coarse_db.h5
	DATABASE1=$(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 BENCH_SECTION=ddfem-adaptive-checked \
	  COARSE_ARGS="--coarse-fallback $(FALLBACK) --coarse-check $(CHECK)" \
	  bash tools/bench_adaptive.sh $(BIN) $(OUT)/bench/ddfem-adaptive-$(ENHANCED_DB)-$(FALLBACK)-checked docs/BENCHMARKS.md \
	  $(OUT)/ddfem/$(ENHANCED_DB).level2.coarse_db.h5

# The same with the full level-1 database for the adaptive runs' level-1
# cells and solve (--level1-database) instead of level 2's compressed base
# (docs/ddfem.md, "Adaptive coarsening", the estimate's shared error).
ddfem-table-adaptive-level1db: stages $(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 $(OUT)/ddfem/$(ENHANCED_DB).level2.coarse_db.h5
	DATABASE1=$(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 BENCH_SECTION=ddfem-adaptive-level1db \
	  COARSE_ARGS="--coarse-fallback $(FALLBACK) --coarse-check $(CHECK)" \
	  ADAPTIVE_ARGS="--level1-database $(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5" \
	  bash tools/bench_adaptive.sh $(BIN) $(OUT)/bench/ddfem-adaptive-$(ENHANCED_DB)-$(FALLBACK)-level1db docs/BENCHMARKS.md \
	  $(OUT)/ddfem/$(ENHANCED_DB).level2.coarse_db.h5

# The same with the a-posteriori check (--posterior-check): a mixed solve
# whose estimate misses the target is followed by a finer one.
ddfem-table-adaptive-posterior: stages $(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 $(OUT)/ddfem/$(ENHANCED_DB).level2.coarse_db.h5
	DATABASE1=$(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 BENCH_SECTION=ddfem-adaptive-posterior \
	  COARSE_ARGS="--coarse-fallback $(FALLBACK) --coarse-check $(CHECK)" \
	  ADAPTIVE_ARGS="--level1-database $(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 --posterior-check" \
	  bash tools/bench_adaptive.sh $(BIN) $(OUT)/bench/ddfem-adaptive-$(ENHANCED_DB)-$(FALLBACK)-posterior docs/BENCHMARKS.md \
	  $(OUT)/ddfem/$(ENHANCED_DB).level2.coarse_db.h5

# The same with the fine model's own estimate (--posterior-estimate newton):
# one fine Newton step from the mixed solution instead of the
# distance from the extrapolated solution.
ddfem-table-adaptive-newton: stages $(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 $(OUT)/ddfem/$(ENHANCED_DB).level2.coarse_db.h5
	DATABASE1=$(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 BENCH_SECTION=ddfem-adaptive-newton \
	  COARSE_ARGS="--coarse-fallback $(FALLBACK) --coarse-check $(CHECK)" \
	  ADAPTIVE_ARGS="--level1-database $(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 --posterior-check --posterior-estimate newton" \
	  bash tools/bench_adaptive.sh $(BIN) $(OUT)/bench/ddfem-adaptive-$(ENHANCED_DB)-$(FALLBACK)-newton docs/BENCHMARKS.md \
	  $(OUT)/ddfem/$(ENHANCED_DB).level2.coarse_db.h5

# Table 2.2 with today's DDFEM model (docs/BENCHMARKS.md, "Table 2.2 with
# today's model"): the enhanced affine databases of both levels, the checked
# lookup (CHECK) and the Galerkin fallback, against naive and averaged
# coarsening on the trilinear element; about 10 minutes.
ddfem-table-current: stages $(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 $(OUT)/ddfem/$(ENHANCED_DB).level2.coarse_db.h5
	BENCH_SECTION=ddfem-current DATABASE2=$(OUT)/ddfem/$(ENHANCED_DB).level2.coarse_db.h5 \
	  DDFEM_ARGS="--coarse-fallback $(FALLBACK) --coarse-check $(CHECK)" \
	  bash tools/bench_ddfem.sh $(BIN) $(OUT)/bench/ddfem-current docs/BENCHMARKS.md $(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5

# The fibre bar of Table 2.2 adaptively (docs/BENCHMARKS.md, "Mixed meshes
# by multigrid"): 330 k unknowns fine, mixed meshes solved by the lattice
# multigrid; about 2 minutes.
ddfem-table-adaptive-fibers: stages $(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 $(OUT)/ddfem/$(ENHANCED_DB).level2.coarse_db.h5
	DATABASE1=$(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 BENCH_SECTION=ddfem-adaptive-fibers TARGETS="0.01 0.005 0.002" \
	  COARSE_ARGS="--coarse-fallback $(FALLBACK) --coarse-check $(CHECK)" \
	  ADAPTIVE_ARGS="--level1-database $(OUT)/ddfem/$(ENHANCED_DB).coarse_db.h5 --posterior-check --posterior-estimate newton" \
	  bash tools/bench_adaptive.sh $(BIN) $(OUT)/bench/ddfem-adaptive-$(ENHANCED_DB)-$(FALLBACK)-fibers docs/BENCHMARKS.md \
	  $(OUT)/ddfem/$(ENHANCED_DB).level2.coarse_db.h5 fibers

# The thesis's own settings (docs/ddfem.md, "The thesis's settings"), level 1:
# palette3.yaml against palette3_thesis.yaml (about 2500 force samples, 500
# stretches, Eq. 2.8's absolute residual) and the two halves of the change
# alone; and palette3 compressed to 100, 400 and 1024 materials, the bases
# that level 2 pairs. Level 2 over 400, 1024 and all 6561 level-1 materials
# (the thesis's choice: about 11 GiB and 40 minutes on 2 cores).
DDFEM_K1_SWEEP := 100 400 1024
DDFEM_L2_BASES := k400 k1024 full
DDFEM_SETTINGS_L1 := palette3 palette3_thesis palette3_eq28fit palette3_thesis_sampling
$(foreach k,$(DDFEM_K1_SWEEP),$(OUT)/ddfem/palette3.k$(k).coarse_db.h5): \
  $(OUT)/ddfem/palette3.k%.coarse_db.h5: $(OUT)/ddfem/palette3.coarse_db.h5 $(STAGE_ID)/msfab-ddfem-compress.id
	$(BIN)/msfab-ddfem-compress --database $< --set representatives=$* --out $@
$(OUT)/ddfem/palette3.full.coarse_db.h5: $(OUT)/ddfem/palette3.coarse_db.h5
	cp $< $@
$(OUT)/ddfem/palette3.level2.%.coarse_db.h5: configs/ddfem/palette3_level2.yaml $(OUT)/ddfem/palette3.%.coarse_db.h5 \
                                             $(STAGE_ID)/msfab-ddfem-build.id
	OMP_NUM_THREADS=$(THREADS) $(MPIRUN) $(BIN)/msfab-ddfem-build --config $< \
	  --set base_database=$(OUT)/ddfem/palette3.$*.coarse_db.h5 --out $@ --resume
.PHONY: ddfem-table-thesis-settings
ddfem-table-thesis-settings: stages $(foreach d,$(DDFEM_SETTINGS_L1),$(OUT)/ddfem/$(d).coarse_db.h5) \
                             $(foreach k,$(DDFEM_K1_SWEEP),$(OUT)/ddfem/palette3.k$(k).coarse_db.h5) \
                             $(foreach b,$(DDFEM_L2_BASES),$(OUT)/ddfem/palette3.level2.$(b).coarse_db.h5)
	BENCH_RUN_LIMIT=120 BENCH_SECTION=ddfem-thesis-settings bash tools/bench_ddfem_databases.sh $(BIN) \
	  $(OUT)/bench/ddfem-settings docs/BENCHMARKS.md $(foreach d,$(DDFEM_SETTINGS_L1),$(d)=$(OUT)/ddfem/$(d).coarse_db.h5) \
	  $(foreach k,$(DDFEM_K1_SWEEP),k$(k)=$(OUT)/ddfem/palette3.k$(k).coarse_db.h5)
	BENCH_RUN_LIMIT=120 LEVEL=2 BENCH_SECTION=ddfem-thesis-settings-level2 bash tools/bench_ddfem_databases.sh $(BIN) \
	  $(OUT)/bench/ddfem-settings docs/BENCHMARKS.md \
	  $(foreach b,$(DDFEM_L2_BASES),over-$(b)=$(OUT)/ddfem/palette3.level2.$(b).coarse_db.h5)
