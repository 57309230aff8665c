# wetcloth: two commands for a new user.
#   make demo   installs what is missing, builds, runs the default scene
#   make test   installs what is missing, builds, runs the test suite (ctest)
BUILD    ?= build
JOBS     ?= $(shell nproc)
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release

.PHONY: all deps build test test-clients test-sanitize test-sanitize-ci fuzz demo validate work-precision same-bits bench clean docs-params readme-params

all: build

deps:
	@tools/install-deps.sh

$(BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD) $(CMAKE_FLAGS)

build: deps $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# The caches in the programs that read them: Blender (rest OBJ + PC2 on a Mesh
# Cache modifier) and VTK's reader; installs blender and python3-vtk9 first.
test-clients: build
	@tools/install-deps.sh clients
	tests/test_clients.sh $(BUILD)/wetcloth $(CURDIR)
# The unit tests, the fuzz corpus and a short run of every built-in scene on 1
# and 2 threads, built with AddressSanitizer and UndefinedBehaviorSanitizer in
# their own folder (any report fails it). Not in CI: it takes too long there
# (docs/guide.md); CI runs test-sanitize-ci below.
SAN_BUILD ?= build-sanitize
SAN_FLAGS = -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
SAN_ENV = ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:strict_string_checks=1 \
          UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
test-sanitize: deps
	cmake -S . -B $(SAN_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS=$(SAN_FLAGS)" \
	  -DWETCLOTH_VIEWER=OFF -DWETCLOTH_BENCH=OFF -DWETCLOTH_BULLET=OFF
	$(SAN_ENV) cmake --build $(SAN_BUILD) -j $(JOBS) --target wetcloth_tests wetcloth_cli fuzz_replay
	cd $(SAN_BUILD) && $(SAN_ENV) ctest --output-on-failure -j $(JOBS) \
	  -E '^(cli|install_and_find_package|plot_scripts|bench_peer_bullet)$$'
	$(SAN_ENV) tests/sanitize_scenes.sh $(SAN_BUILD)/wetcloth

# The sanitizer check CI runs (.ci/run), sized to fit its time: ASan + UBSan at
# -O1 in build-sanitize-ci, the library and the program alone (no viewer,
# Python or benchmarks), a subset of the unit tests (wetcloth_tests_subset,
# tests/CMakeLists.txt), the fuzz corpus replay, the fault and signal tests,
# the kill-and-resume test and a short run of every built-in scene on 1 and 2
# threads. About 20 minutes on a fresh clone on 2 idle cores (estimated from
# CPU times; docs/performance.md).
SAN_CI_BUILD ?= build-sanitize-ci
# Two tests of the subset take 1.5 and 2.5 minutes under the sanitizers: left to make test-sanitize.
SAN_CI_UNIT_FILTER = -StrainLimit.NoStructuralSpringEndsLongerThanTheLimit:SelfCollision.KeepsTwoFoldedLayersApart
test-sanitize-ci: deps
	cmake -S . -B $(SAN_CI_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" "-DCMAKE_CXX_FLAGS=$(SAN_FLAGS)" \
	  -DWETCLOTH_VIEWER=OFF -DWETCLOTH_BENCH=OFF -DWETCLOTH_BULLET=OFF -DWETCLOTH_PYTHON=OFF
	$(SAN_ENV) cmake --build $(SAN_CI_BUILD) -j $(JOBS) --target wetcloth_cli fuzz_replay wetcloth_tests_subset
	$(SAN_ENV) $(SAN_CI_BUILD)/tests/wetcloth_tests_subset --gtest_filter=$(SAN_CI_UNIT_FILTER)
	$(SAN_ENV) $(SAN_CI_BUILD)/tests/fuzz_replay tests/fuzz-corpus
	$(SAN_ENV) tests/test_faults.sh $(SAN_CI_BUILD)/wetcloth
	$(SAN_ENV) tests/test_resume.sh $(SAN_CI_BUILD)/wetcloth
	$(SAN_ENV) tests/sanitize_scenes.sh $(SAN_CI_BUILD)/wetcloth

# The scene loader's libFuzzer target (clang, ASan + UBSan, in build-fuzz), for
# FUZZ_SECONDS; new inputs go to build-fuzz/corpus, crashes to build-fuzz/crashes
# (add them to tests/fuzz-corpus, which `make test` replays).
FUZZ_BUILD ?= build-fuzz
FUZZ_SECONDS ?= 60
fuzz:
	@tools/install-deps.sh fuzz
	CC=clang CXX=clang++ cmake -S . -B $(FUZZ_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  "-DCMAKE_CXX_FLAGS=-fsanitize=address,undefined,fuzzer-no-link -fno-sanitize-recover=all" \
	  -DWETCLOTH_FUZZ=ON -DWETCLOTH_TESTS=OFF -DWETCLOTH_VIEWER=OFF -DWETCLOTH_BENCH=OFF -DWETCLOTH_BULLET=OFF
	cmake --build $(FUZZ_BUILD) -j $(JOBS) --target wetcloth_fuzz
	mkdir -p $(FUZZ_BUILD)/corpus $(FUZZ_BUILD)/crashes
	$(FUZZ_BUILD)/wetcloth_fuzz -max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=4096 \
	  -max_len=65536 -print_final_stats=1 -artifact_prefix=$(FUZZ_BUILD)/crashes/ \
	  $(FUZZ_BUILD)/corpus tests/fuzz-corpus

demo: build
	$(BUILD)/wetcloth run pull-straight --humidity 0.7 --out out/demo
	@echo "results: out/demo (metrics.csv, frames/*.obj, summary.json, scene.toml)"
	@if [ -x $(BUILD)/python/python ]; then \
	  echo "from Python: $(BUILD)/python/python (the interpreter the module was built for, $$(sed -n 's/^PYTHON = \"\(.*\)\"/\1/p' $(BUILD)/python/wetcloth/_build.py), with PYTHONPATH=$(BUILD)/python)"; \
	fi

validate: build
	tools/validate.sh $(BUILD)

# Each integrator setting's cost against its error on the paper's scenes at
# ω = 0, 0.7 and 1 (docs/performance.md; validate runs it too): about an hour
# on two cores.
work-precision: build
	/usr/bin/python3 tools/work_precision.py $(BUILD) --out out/work-precision \
	  --scenes pull-straight,pull-oblique,pull-corner,drag-corner,drape-ball,peel-rig

# Whether the current build gives the numbers of REV (default HEAD~1) bit for
# bit on every built-in scene: a refactoring must.
REV ?= HEAD~1
same-bits: build
	tools/same-bits.sh $(REV) $(BUILD)

# The micro-benchmarks; then, in a build with Bullet (libbullet-dev found when
# configured), our step beside Bullet's btSoftBody on the same cloth, taking
# turns in one process (`wetcloth bench --peer bullet`): the bench's scene and a
# plain hanging cloth, at 51 x 51 and 201 x 201 (3 minutes on the 2 cores, busy).
PEER = $(BUILD)/wetcloth bench --peer bullet
bench: build
	$(BUILD)/wetcloth_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
	@if grep -qx 'WETCLOTH_HAVE_BULLET:INTERNAL=ON' $(BUILD)/CMakeCache.txt; then \
	  set -ex; \
	  $(PEER) --grids 51 --duration 0.1 --repetitions 7 --out out/bench_bullet_51.json; \
	  $(PEER) --scene hang --grids 51 --duration 0.1 --repetitions 7 --out out/bench_bullet_hang_51.json; \
	  $(PEER) --grids 201 --duration 0.02 --repetitions 3 --out out/bench_bullet_201.json; \
	  $(PEER) --scene hang --grids 201 --duration 0.02 --repetitions 3 --out out/bench_bullet_hang_201.json; \
	else \
	  echo "this build has no Bullet (libbullet-dev not found): no 'wetcloth bench --peer bullet'"; \
	fi

# Regenerate the user guide's parameter table (docs/guide.md) from the
# loader's own definitions; readme-params is its old name.
docs-params: build
	tools/update-docs-params.sh $(BUILD)/wetcloth

readme-params: docs-params

clean:
	rm -rf $(BUILD)
