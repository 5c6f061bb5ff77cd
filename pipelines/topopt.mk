# Two-scale topology optimization and its full-resolution check (thesis
# §3.4–3.6, Table 3.1): gamut -> design -> mapping -> homogenized against
# voxel simulation.
#
#   make -f Makefile.pipeline topopt-bar-check   the 8x2x2 bar of Table 3.1: 16^3 gamut (minutes), design,
#                                                mapping, check on 128x32x32 voxels (docs/verify_map.md)
#
# Writes out/topopt/bar.{design,mapped}.h5 and three checks, one summary
# line each: bar.verify.h5 (the thesis's comparison: one hexahedron per
# cell), bar.h4.verify.h5 (the homogenized model with 4^3 hexahedra per cell:
# the homogenization's own error, without most of the coarse mesh's
# stiffness) and bar.solid.verify.h5 (every cell solid: the coarse mesh's
# error alone). SEED (pipelines/gamut.mk) seeds the gamut and the mapping.
BAR_GAMUT := $(OUT)/gamut/cubic3d_bar

$(BAR_GAMUT).microstructures.h5: $(BAR_GAMUT).gamut.h5
	@test -s $@

$(OUT)/topopt/bar.design.h5: configs/topopt/bar.yaml $(BAR_GAMUT).gamut.h5 $(BIN)/msfab-topopt
	@mkdir -p $(@D)
	$(BIN)/msfab-topopt --config $< --set gamut=$(BAR_GAMUT).gamut.h5 --threads $(THREADS) --out $@ --quiet

$(OUT)/topopt/bar.mapped.h5: $(OUT)/topopt/bar.design.h5 $(BAR_GAMUT).microstructures.h5 $(BIN)/msfab-map
	$(BIN)/msfab-map --design $< --structures $(BAR_GAMUT).microstructures.h5 --seed $(SEED) \
	  --threads $(THREADS) --out $@ --quiet

$(OUT)/topopt/bar.verify.h5: $(OUT)/topopt/bar.mapped.h5 $(OUT)/topopt/bar.design.h5 $(BIN)/msfab-verify-map
	$(BIN)/msfab-verify-map --design $(OUT)/topopt/bar.design.h5 --mapped $< \
	  --structures $(BAR_GAMUT).microstructures.h5 --threads $(THREADS) --out $@

$(OUT)/topopt/bar.h4.verify.h5: $(OUT)/topopt/bar.mapped.h5 $(OUT)/topopt/bar.design.h5 $(BIN)/msfab-verify-map
	$(BIN)/msfab-verify-map --design $(OUT)/topopt/bar.design.h5 --mapped $< \
	  --structures $(BAR_GAMUT).microstructures.h5 --set homogenized_elements=4 --threads $(THREADS) --out $@

$(OUT)/topopt/bar.solid.verify.h5: $(OUT)/topopt/bar.mapped.h5 $(OUT)/topopt/bar.design.h5 $(BIN)/msfab-verify-map
	$(BIN)/msfab-verify-map --design $(OUT)/topopt/bar.design.h5 --mapped $< \
	  --structures $(BAR_GAMUT).microstructures.h5 --set fill=solid --threads $(THREADS) --out $@

.PHONY: topopt-bar-check
topopt-bar-check: build $(OUT)/topopt/bar.verify.h5 $(OUT)/topopt/bar.h4.verify.h5 $(OUT)/topopt/bar.solid.verify.h5
