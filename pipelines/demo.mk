# Demo pipeline: the heterogeneous bar scene through msfab-simulate.
$(OUT)/demo/bar.result.h5: configs/scenes/demo_bar.yaml $(BIN)/msfab-simulate
	@mkdir -p $(@D)
	$(BIN)/msfab-simulate --config $< --out $@ --threads $(THREADS)
