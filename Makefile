# wetcloth: two commands for a new user.
#   make demo   installs what is missing, builds, runs the default scene
#   make test   installs what is missing, builds, runs the test suite (ctest)
BUILD    ?= build
JOBS     ?= $(shell nproc)
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release

.PHONY: all deps build test demo validate bench clean readme-params

all: build

deps:
	@tools/install-deps.sh

$(BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD) $(CMAKE_FLAGS)

build: deps $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

demo: build
	$(BUILD)/wetcloth run pull-straight --humidity 0.7 --out out/demo
	@echo "results: out/demo (metrics.csv, frames/*.obj, summary.json, scene.toml)"

validate: build
	tools/validate.sh $(BUILD)

bench: build
	$(BUILD)/wetcloth_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true

# Regenerate the README's parameter table from the loader's own definitions.
readme-params: build
	tools/update-readme-params.sh $(BUILD)/wetcloth

clean:
	rm -rf $(BUILD)
