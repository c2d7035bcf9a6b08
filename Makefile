# scandiff: the two commands of the README.
#   make run    installs dependencies, builds, starts the workbench on the demo data
#   make test   installs dependencies, builds, runs every test
# And for reliability work (docs/reliability.md):
#   make sanitize   every test but the GUI's, built with AddressSanitizer and UndefinedBehaviorSanitizer
#   make fuzz       each reader's libFuzzer harness for FUZZ_SECONDS (default 1800) seconds
BUILD_DIR ?= build
BUILD_TYPE ?= Release
JOBS ?= $(shell nproc)
DEMO_FILES ?= data/demo/site-2019.ply data/demo/site-2024.ply
SANITIZE_DIR ?= build-sanitize
FUZZ_SECONDS ?= 1800

.PHONY: all deps configure build run test bench sanitize fuzz clean

all: build

deps:
	./scripts/install-deps.sh

$(BUILD_DIR)/build.ninja:
	cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=$(BUILD_TYPE)

configure: deps $(BUILD_DIR)/build.ninja

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

run: build
	$(BUILD_DIR)/app/gui/scandiff $(DEMO_FILES)

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

# -O1 -g1: fast enough to run, lines in the reports. A leak, an invalid access
# or any undefined behaviour fails the test that met it.
sanitize: deps
	cmake -S . -B $(SANITIZE_DIR) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" \
	  -DSCANDIFF_SANITIZE=ON -DSCANDIFF_BUILD_GUI=OFF -DSCANDIFF_BUILD_BENCH=OFF
	cmake --build $(SANITIZE_DIR) -j $(JOBS)
	cd $(SANITIZE_DIR) && ASAN_OPTIONS=detect_leaks=1:check_initialization_order=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --output-on-failure -j $(JOBS)

fuzz:
	./scripts/fuzz.sh $(FUZZ_SECONDS)

bench: build
	./bench/run-benchmarks.sh $(BUILD_DIR)

clean:
	rm -rf $(BUILD_DIR) $(SANITIZE_DIR) build-fuzz
