# wetcloth: two commands for a new user.
#   make demo   installs what is missing, builds, runs the default scene
#   make test   installs what is missing, builds, runs the test suite (ctest)
BUILD    ?= build
JOBS     ?= $(shell nproc)
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release

.PHONY: all deps build test test-clients demo validate bench clean docs-params readme-params

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

demo: build
	$(BUILD)/wetcloth run pull-straight --humidity 0.7 --out out/demo
	@echo "results: out/demo (metrics.csv, frames/*.obj, summary.json, scene.toml)"

validate: build
	tools/validate.sh $(BUILD)

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
