# The static scenes of thesis Table 2.2 at full resolution:
#   make -f Makefile.pipeline static-scenes          all of them
#   make -f Makefile.pipeline out/scenes/bending.result.h5
STATIC_SCENES := pushing bending twisting buckling fibers

$(OUT)/scenes/%.result.h5: configs/scenes/%.yaml $(STAGE_ID)/msfab-simulate.id
	@mkdir -p $(@D)
	$(BIN)/msfab-simulate --config $< --out $@ --threads $(THREADS)

.PHONY: static-scenes
static-scenes: stages $(STATIC_SCENES:%=$(OUT)/scenes/%.result.h5)
