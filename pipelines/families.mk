# Extremal microstructure families (thesis §3.3, Appendix A; docs/families.md).
#
#   make -f Makefile.pipeline families-demo    two hand-made families (a lattice and a frame, 30 members
#                                              each) homogenized and found again; seconds
#   make -f Makefile.pipeline families-gamut   a random 3D cubic set of ~1500 structures at 16^3 (minutes),
#                                              families among its nu > 0.3 structures and among its auxetic
#                                              ones (if any)
#   make -f Makefile.pipeline families-auxetic  auxetic families of the 3D gamut with directed min_nu pushes
#                                              (gamut-auxetic-3d, ~2 min, then seconds)
#   make -f Makefile.pipeline families-auxetic-32  the same on the 32^3 gamut (gamut-auxetic-3d-32, ~15 min;
#                                              families of >= 3 members: it holds 7 auxetic structures)
#   make -f Makefile.pipeline families-auxetic-check  every member of the first auxetic family (16^3) under
#                                              finite uniaxial stress, Neo-Hookean, against linear C^H; a minute
#
# Writes out/families/{two,stiff_nu}.families.h5 with a picture per family
# in *.plots/, and a sweep of each family's first reduced parameter (*.family1.microstructures.h5).
$(OUT)/families/two.microstructures.h5: configs/families/two_templates.yaml $(STAGE_ID)/msfab-family-generate.id
	@mkdir -p $(@D)
	$(BIN)/msfab-family-generate --config $< --threads $(THREADS) --out $@ $(QUIET)

$(OUT)/families/two.families.h5: $(OUT)/families/two.microstructures.h5 $(STAGE_ID)/msfab-families.id
	$(BIN)/msfab-families --structures $< --set 'selection.nu=[-1,0.5]' --set min_members=10 \
	  --seed $(SEED) --threads $(THREADS) --out $@

$(OUT)/families/%.family1.microstructures.h5: $(OUT)/families/%.families.h5 $(STAGE_ID)/msfab-family-generate.id
	$(BIN)/msfab-family-generate --families $< --family 1 --sweep 5 --threads $(THREADS) --out $@

$(OUT)/families/stiff_nu.families.h5: configs/families/stiff_nu.yaml $(OUT)/gamut/cubic3d_families.gamut.h5 \
    $(STAGE_ID)/msfab-families.id
	@mkdir -p $(@D)
	$(BIN)/msfab-families --config $< --structures $(OUT)/gamut/cubic3d_families.microstructures.h5 \
	  --seed $(SEED) --threads $(THREADS) --out $@

$(OUT)/families/auxetic_directed.families.h5: configs/families/auxetic_directed.yaml \
    $(OUT)/gamut/cubic3d_auxetic.gamut.h5 $(STAGE_ID)/msfab-families.id
	@mkdir -p $(@D)
	$(BIN)/msfab-families --config $< --structures $(OUT)/gamut/cubic3d_auxetic.microstructures.h5 \
	  --seed $(SEED) --threads $(THREADS) --out $@

$(OUT)/families/auxetic_directed_32.families.h5: configs/families/auxetic_directed.yaml \
    $(OUT)/gamut/cubic3d_auxetic_32.gamut.h5 $(STAGE_ID)/msfab-families.id
	@mkdir -p $(@D)
	$(BIN)/msfab-families --config $< --structures $(OUT)/gamut/cubic3d_auxetic_32.microstructures.h5 \
	  --set min_members=3 --seed $(SEED) --threads $(THREADS) --out $@

.PHONY: families-demo families-gamut families-auxetic families-auxetic-32 families-auxetic-check
families-auxetic: stages $(OUT)/families/auxetic_directed.families.h5
families-auxetic-32: stages $(OUT)/families/auxetic_directed_32.families.h5
families-auxetic-check: stages $(OUT)/families/auxetic_directed.families.h5
	bash tools/bench_finite_strain.sh $(BIN) $(OUT)/gamut/cubic3d_auxetic.microstructures.h5 \
	  $(OUT)/families/auxetic_directed.families.h5 0 $(OUT)/families/finite_strain
families-demo: stages $(OUT)/families/two.families.h5 $(OUT)/families/two.family1.microstructures.h5
families-gamut: stages $(OUT)/families/stiff_nu.families.h5
	@# The auxetic selection of the same set (an input error when it holds none).
	-$(BIN)/msfab-families --config configs/families/auxetic.yaml \
	  --structures $(OUT)/gamut/cubic3d_families.microstructures.h5 --seed $(SEED) --threads $(THREADS) \
	  --out $(OUT)/families/auxetic.families.h5
