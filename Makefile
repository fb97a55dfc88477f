# Thin front door. The README's two commands: `make demo` and `make test`.
BUILD_DIR ?= build
JOBS ?= 2
BUILD_TYPE ?= RelWithDebInfo
CMAKE_ARGS ?=
# Fuzzing (tests/fuzz/README.md): a separate clang build, each target run FUZZ_SECONDS;
# FUZZ_TARGETS: a subset (default: every target); FUZZ_SEED: libFuzzer's seed (0: random).
FUZZ_BUILD_DIR ?= build-fuzz
FUZZ_SECONDS ?= 60
FUZZ_TARGETS ?=
FUZZ_SEED ?= 0
FUZZ_CMAKE_ARGS ?=

# ccache (installed by deploy/install-deps.sh, used by cmake/ConcertProject.cmake): paths below
# the source tree are hashed relative to it, so a clone in another folder (CI's) reuses the cache.
export CCACHE_BASEDIR ?= $(CURDIR)
export CCACHE_NOHASHDIR ?= 1

.PHONY: all deps configure build image test demo bench chaos shift fuzz fuzz-configure fuzz-smoke idl-lock clean help

all: build

help:
	@echo "make demo   install what is missing, build, run the stack in simulation"
	@echo "make image  the deployment's container image from this build (deploy/README.md)"
	@echo "make test   install what is missing, build, run every test with ctest"
	@echo "make bench  build and run the benchmarks (BENCHES=\"bench_x ...\": some); figures go to docs/benchmarks.md"
	@echo "make chaos  the chaos test: SIGKILL every service of concert up under a task"
	@echo "make shift  a crew's shift on one stack (SHIFT_ARGS=\"--rounds 3 --load 2\")"
	@echo "make fuzz   clang build of the fuzz targets, each run FUZZ_SECONDS (default 60)"
	@echo "make fuzz-smoke  CI's short fuzz run (5 s a target, fixed seed, fuzz_cli left out)"
	@echo "make idl-lock  rewrite idl/types.lock after changing a message type"
	@echo "make deps | build | clean"

deps:
	./deploy/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(CMAKE_ARGS)

build: configure
	cmake --build $(BUILD_DIR) -j$(JOBS)

# The runtime image of the deployment from this build tree (deploy/README.md); the compose
# test of `make test` runs it. IMAGE: its name.
IMAGE ?= concert/stack:latest
image: build
	CONCERT_IMAGE=$(IMAGE) ./deploy/image/build.sh $(BUILD_DIR)

# The compose test needs root (namespaces, podman as root): without it, no image is made and
# ctest reports that test skipped.
test: build
	@if [ "$$(id -u)" -eq 0 ]; then $(MAKE) --no-print-directory image; \
	 else echo "make test: not root: no image made; deploy_compose_test will be skipped"; fi
	cd $(BUILD_DIR) && CONCERT_IMAGE=$(IMAGE) ctest --output-on-failure -j$(JOBS) --timeout 300

demo: build
	./deploy/demo.sh $(BUILD_DIR)

# BENCHES: a subset of the bench_* programs (default: all); figures go to docs/benchmarks.md.
BENCHES ?=
bench: build
	./deploy/bench.sh $(BUILD_DIR) $(BENCHES)

# The chaos test alone (tests/system/README.md; make test runs it too): SIGKILLs every service
# of `concert up` under a task. CHAOS_DOMAIN: its DDS domain.
CHAOS_DOMAIN ?= 231
chaos: build
	CONCERT_DOMAIN_ID=$(CHAOS_DOMAIN) $(BUILD_DIR)/tests/system/system_chaos_test

# A crew's shift on one simulated stack (tests/system/README.md, bench_shift): drilling, hot
# swaps, sanding, spraying, round after round. SHIFT_ARGS: e.g. --rounds 3 --load 2 --seed 7.
SHIFT_ARGS ?=
SHIFT_DOMAIN ?= 44
shift: build
	CONCERT_DOMAIN_ID=$(SHIFT_DOMAIN) $(BUILD_DIR)/tests/system/bench_shift $(SHIFT_ARGS)

# The fuzzing build: clang-16 with libFuzzer, ASan and UBSan, assertions on, -O1; only the fuzz
# targets and what they link are built. Warnings are not errors there (clang warns where gcc,
# which the project is written against, does not).
fuzz-configure: deps
	cmake -S . -B $(FUZZ_BUILD_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DCMAKE_C_COMPILER=clang-16 -DCMAKE_CXX_COMPILER=clang++-16 \
	  -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" \
	  -DCONCERT_FUZZ=ON -DCONCERT_WERROR=OFF $(FUZZ_CMAKE_ARGS)

fuzz: fuzz-configure
	cmake --build $(FUZZ_BUILD_DIR) -j$(JOBS) --target $(if $(FUZZ_TARGETS),$(FUZZ_TARGETS),fuzz_all)
	FUZZ_SEED=$(FUZZ_SEED) ./tests/fuzz/run.sh $(FUZZ_BUILD_DIR) $(FUZZ_SECONDS) $(FUZZ_TARGETS)

# CI (every run, .ci/run): every target but the heavy fuzz_cli, 5 s each with a fixed seed
# (regressions of all of them replay in `make test`).
fuzz-smoke: fuzz-configure
	cmake --build $(FUZZ_BUILD_DIR) -j$(JOBS) --target fuzz_smoke
	FUZZ_SEED=1 ./tests/fuzz/run.sh $(FUZZ_BUILD_DIR) 5 --smoke

# After changing a message type: rewrite idl/types.lock (review its diff, commit both).
idl-lock: configure
	cmake --build $(BUILD_DIR) -j$(JOBS) --target idl-lock

clean:
	rm -rf $(BUILD_DIR) $(FUZZ_BUILD_DIR)
