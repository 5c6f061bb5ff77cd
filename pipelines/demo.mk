# Demo pipeline: the heterogeneous bar scene through msfab-simulate.
$(OUT)/demo/bar.result.h5: configs/scenes/demo_bar.yaml $(STAGE_ID)/msfab-simulate.id
	@mkdir -p $(@D)
	$(BIN)/msfab-simulate --config $< --out $@ --threads $(THREADS)

# The same bar coarsened with the tiny DDFEM database, compared with the
# fine result above (error and speedup are printed and stored).
$(OUT)/demo/bar.ddfem.result.h5: configs/scenes/demo_bar.yaml $(OUT)/ddfem/tiny.coarse_db.h5 \
                                 $(OUT)/demo/bar.result.h5 $(STAGE_ID)/msfab-simulate.id
	@mkdir -p $(@D)
	$(BIN)/msfab-simulate --config $< --coarsen 1 --database $(word 2,$^) --reference $(word 3,$^) \
	  --out $@ --threads $(THREADS)

# The demo's pictures: speed against error and Newton convergence of the two
# runs above (python/msfab/report.py; `make report` draws every artifact).
$(OUT)/demo/report.html: $(OUT)/demo/bar.result.h5 $(OUT)/demo/bar.ddfem.result.h5 $(wildcard python/msfab/*.py)
	PYTHONPATH=$(CURDIR)/python $(PYTHON) -m msfab report --title "msfab demo" $@ $(filter %.h5,$^)
