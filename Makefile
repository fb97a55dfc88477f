# Thin front door. The README's two commands: `make demo` and `make test`.
BUILD_DIR ?= build
JOBS ?= 2
BUILD_TYPE ?= RelWithDebInfo
CMAKE_ARGS ?=

.PHONY: all deps configure build test demo bench idl-lock clean help

all: build

help:
	@echo "make demo   install what is missing, build, run the stack in simulation"
	@echo "make test   install what is missing, build, run every test with ctest"
	@echo "make bench  build and run the benchmarks (figures go in README.md)"
	@echo "make idl-lock  rewrite idl/types.lock after changing a message type"
	@echo "make deps | build | clean"

deps:
	./deploy/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(CMAKE_ARGS)

build: configure
	cmake --build $(BUILD_DIR) -j$(JOBS)

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j$(JOBS) --timeout 300

demo: build
	./deploy/demo.sh $(BUILD_DIR)

bench: build
	./deploy/bench.sh $(BUILD_DIR)

# After changing a message type: rewrite idl/types.lock (review its diff, commit both).
idl-lock: configure
	cmake --build $(BUILD_DIR) -j$(JOBS) --target idl-lock

clean:
	rm -rf $(BUILD_DIR)
