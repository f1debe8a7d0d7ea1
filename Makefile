# Two commands do everything on a fresh Debian 12 machine (as root):
#   make demo   set up what is missing, then build every output under build/
#   make test   set up what is missing, then run the test suite
PY := .venv/bin/python

.PHONY: demo test test-fast bootstrap clean
bootstrap:
	@./bootstrap.sh

demo: bootstrap
	@$(PY) -m platform_tools.demo --out build

# pytest exits 5 when it collected no test: that is a failure here, not a pass.
# Every core (pytest-xdist; --dist loadfile keeps a file's tests, and its module fixtures, on one worker);
# the 25 slowest tests are listed at the end, for whoever needs to trim the suite.
PARALLEL := -n auto --dist loadfile

test: bootstrap
	@$(PY) -m pytest $(PARALLEL) --durations=25 $(PYTEST_ARGS); rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "make test: pytest collected no tests" >&2; fi; \
	exit $$rc

# the quick loop while developing (under 90 s on 2 cores): every test not marked slow
test-fast: bootstrap
	@$(PY) -m pytest -q -m "not slow" $(PARALLEL) $(PYTEST_ARGS); rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "make test-fast: pytest collected no tests" >&2; fi; \
	exit $$rc

clean:
	rm -rf build
