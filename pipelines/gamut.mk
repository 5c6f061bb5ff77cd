# Microstructure gamuts (thesis §3.2): sampling runs and the coverage benchmark.
#
#   make -f Makefile.pipeline gamut-2d       2D cubic gamut, stiff + soft (configs/gamut/cubic2d.yaml), a minute
#   make -f Makefile.pipeline gamut-ortho    2D orthotropic gamut, minutes
#   make -f Makefile.pipeline gamut-2d-void  2D cubic and orthotropic gamuts of one material + void (Fig. 3-16), minutes
#   make -f Makefile.pipeline gamut-2d-three 2D cubic gamut of two materials (1000x apart) + void (Fig. 3-15), minutes
#   make -f Makefile.pipeline gamut-auxetic-2d  2D cubic void gamut at 32^2 with min_nu pushes (nu to -0.8), minutes
#   make -f Makefile.pipeline gamut-auxetic-2d-printable  the same at 48^2, no feature below 2 voxels, ~5 min
#   make -f Makefile.pipeline gamut-auxetic-3d  3D cubic void gamut at 16^3 with min_nu pushes, ~2 min
#   make -f Makefile.pipeline gamut-auxetic-3d-32  the same at 32^3 (lengths in voxels doubled), ~10 min
#   make -f Makefile.pipeline gamut-auxetic-3d-64  at 64^3, started from the 16^3 gamut's structures, ~45 min
#   make -f Makefile.pipeline gamut-3d       3D cubic gamut, one material + void, 16^3 cells; hours on 2 cores, use RANKS
#   make -f Makefile.pipeline gamut-converge-2d  2D cubic, orthotropic (stiff + soft and one material + void) and 2D
#                                             cubic of two materials + void run
#                                             until the coverage stops growing (out/gamut/converged/), tens of minutes
#   make -f Makefile.pipeline gamut-converge-3d  the same for the 3D cubic void gamut; hours on 2 cores, use RANKS
#   make -f Makefile.pipeline gamut-bench    sampler vs random sampling, docs/BENCHMARKS.md section
#
# Each run writes out/gamut/<name>.gamut.h5 and <name>.microstructures.h5
# (`make report` draws them). RANKS=<n> runs
# on n MPI ranks; an interrupted run resumes from its checkpoint when the
# target is made again. SEED=<n> picks the random streams.
SEED ?= 1
# Runs to convergence: stop once the best coverage so far grew by less than
# CONVERGE_GROWTH (relative) over CONVERGE_WINDOW cycles, at most
# CONVERGE_CYCLES cycles (docs/gamut.md, "Runs to convergence").
CONVERGE_GROWTH ?= 0.01
CONVERGE_WINDOW ?= 10
CONVERGE_CYCLES ?= 300

$(OUT)/gamut/%.gamut.h5: configs/gamut/%.yaml $(STAGE_ID)/msfab-gamut-sample.id
	@mkdir -p $(@D)
	OMP_NUM_THREADS=$(THREADS) $(MPIRUN) $(BIN)/msfab-gamut-sample --config $< --seed $(SEED) --out $@ --resume

$(OUT)/gamut/converged/%.gamut.h5: configs/gamut/%.yaml $(STAGE_ID)/msfab-gamut-sample.id
	@mkdir -p $(@D)
	OMP_NUM_THREADS=$(THREADS) $(MPIRUN) $(BIN)/msfab-gamut-sample --config $< --seed $(SEED) --out $@ --resume \
	  --set cycles=$(CONVERGE_CYCLES) --set plot_every_cycle=false \
	  --set stop='{coverage_growth: $(CONVERGE_GROWTH), window: $(CONVERGE_WINDOW)}'

.PHONY: gamut-converge-2d gamut-converge-3d
gamut-converge-2d: stages $(addprefix $(OUT)/gamut/converged/,cubic2d.gamut.h5 orthotropic2d.gamut.h5 cubic2d_void.gamut.h5 \
    orthotropic2d_void.gamut.h5 cubic2d_three.gamut.h5)
gamut-converge-3d: stages $(OUT)/gamut/converged/cubic3d_void.gamut.h5

.PHONY: gamut-2d gamut-ortho gamut-2d-void gamut-2d-three gamut-auxetic-2d gamut-auxetic-2d-printable gamut-auxetic-3d gamut-auxetic-3d-32 gamut-auxetic-3d-64 gamut-3d gamut-bench
gamut-2d: stages $(OUT)/gamut/cubic2d.gamut.h5
gamut-ortho: stages $(OUT)/gamut/orthotropic2d.gamut.h5
gamut-2d-void: stages $(OUT)/gamut/cubic2d_void.gamut.h5 $(OUT)/gamut/orthotropic2d_void.gamut.h5
gamut-2d-three: stages $(OUT)/gamut/cubic2d_three.gamut.h5
gamut-auxetic-2d: stages $(OUT)/gamut/cubic2d_auxetic.gamut.h5
gamut-auxetic-2d-printable: stages $(OUT)/gamut/cubic2d_auxetic_printable.gamut.h5
gamut-auxetic-3d: stages $(OUT)/gamut/cubic3d_auxetic.gamut.h5
gamut-auxetic-3d-32: stages $(OUT)/gamut/cubic3d_auxetic_32.gamut.h5
gamut-auxetic-3d-64: stages $(OUT)/gamut/cubic3d_auxetic_64.gamut.h5
$(OUT)/gamut/cubic3d_auxetic_64.gamut.h5: $(OUT)/gamut/cubic3d_auxetic.gamut.h5
gamut-3d: stages $(OUT)/gamut/cubic3d_void.gamut.h5

gamut-bench: stages
	bash tools/bench_gamut.sh $(BIN) $(OUT)/bench/gamut docs/BENCHMARKS.md
