# The project's commands. See README.md.
PY     := $(CURDIR)/.venv/bin/python
BUILD  := build
FUZZ_BUILD   := build-fuzz
FUZZ_SECONDS := 60

.PHONY: setup build vm fuzz-build fuzz test bench demo lint clean

setup:            ## install Debian + pinned PyPI dependencies, create .venv (idempotent; root)
	bash scripts/setup.sh

build:            ## configure and build the C++ host library, tests and Python bindings
	@test -x $(PY) || { echo "run 'make setup' first"; exit 1; }
	cmake -S . -B $(BUILD) -G Ninja -DPython_EXECUTABLE=$(PY) -Wno-dev > /dev/null
	cmake --build $(BUILD)

vm:               ## the device test VM's modules and initramfs (tests/vm; cached in .cache/vm-*)
	@test -x $(PY) || { echo "run 'make setup' first"; exit 1; }
	$(PY) tests/vm/build.py

fuzz-build:       ## the libFuzzer targets (clang, ASan + UBSan) in their own build directory
	@test -x $(PY) || { echo "run 'make setup' first"; exit 1; }
	CC=clang CXX=clang++ cmake -S . -B $(FUZZ_BUILD) -G Ninja -DMOCAP_FUZZ=ON \
	  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPython_EXECUTABLE=$(PY) -Wno-dev > /dev/null
	cmake --build $(FUZZ_BUILD)

fuzz: fuzz-build  ## every fuzz target for FUZZ_SECONDS each: one JSON line per target
	nice -n 5 $(PY) scripts/fuzz.py --build $(FUZZ_BUILD) --seconds $(FUZZ_SECONDS)

test: setup build fuzz-build vm ## every test of every part (installs what is missing first)
	ctest --test-dir $(BUILD) --output-on-failure
	ctest --test-dir $(FUZZ_BUILD) --output-on-failure
	$(PY) -m pytest -q

demo: setup build ## the live demo on a simulated studio: out/demo.bvh, out/report.md
	$(PY) -m mocap.cli demo --out out

bench: build      ## benchmarks, one JSON object per line
	@OPENBLAS_NUM_THREADS=1 $(PY) -m mocap.cli bench

clean:
	rm -rf build $(FUZZ_BUILD)

lint:             ## formatting of the C++ code, static checks of the Python code, its rooms and sizes, options declared everywhere
	clang-format --dry-run -Werror $$(git ls-files 'host/*.cc' 'host/*.h' 'edge/*.cc' 'edge/*.h')
	$(CURDIR)/.venv/bin/ruff check host/python edge/python tests firmware yocto/tests scripts/edge_dist.py conftest.py
	$(CURDIR)/.venv/bin/lint-imports pyproject.toml
	$(PY) scripts/check_sizes.py host edge firmware tests yocto
	@test -f host/python/mocap/_core*.so || { echo "run 'make build' first (the options check reads the bindings)"; exit 1; }
	$(PY) -m pytest -q host/python/tests/test_options_fields.py host/python/tests/test_session.py
