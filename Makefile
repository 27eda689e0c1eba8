# vpm: the two commands a new user runs are `make demo` and `make test`.
# Both install missing Debian packages (scripts/install-deps.sh) and the web
# viewer's npm packages (scripts/install-web.sh), configure and build first.
# `make serve` starts vpm-server and the web viewer's gateway.
BUILD_DIR ?= build
BUILD_TYPE ?= RelWithDebInfo
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=
# The compilers of the main tree: Debian's clang 14 (it compiles the project
# in about a third less CPU time than GCC 12, and its code is as fast:
# docs/benchmarks/CI_TIME.md) unless given, e.g. `make test CC=gcc CXX=g++`.
ifeq ($(origin CC),default)
CC := clang
endif
ifeq ($(origin CXX),default)
CXX := clang++
endif

.PHONY: all deps web-deps configure build test demo serve bench fuzz asan tsan clean format

all: build

deps:
	@scripts/install-deps.sh

# npm ci of client/web from its lockfile; skipped when already current.
web-deps: deps
	@scripts/install-web.sh

configure: deps
	@scripts/configure.sh $(BUILD_DIR) $(CC) $(CXX) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(CMAKE_FLAGS)
	@echo "configured $(BUILD_DIR) ($(BUILD_TYPE), $(CXX))"

build: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS)

test: build web-deps
	@cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS) --timeout 600

demo: build web-deps
	@scripts/demo.sh $(BUILD_DIR)

serve: build web-deps
	@scripts/serve.sh $(BUILD_DIR)

bench: build
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target benches
	@scripts/bench.sh $(BUILD_DIR)

# The service, render and FEM tests under AddressSanitizer + UBSan, or
# ThreadSanitizer (scripts/sanitize.sh says which tests).
asan: deps
	@scripts/sanitize.sh address

tsan: deps
	@scripts/sanitize.sh thread

fuzz: deps
	@scripts/fuzz.sh 60

format:
	@git ls-files '*.h' '*.cc' | xargs clang-format -i

clean:
	rm -rf $(BUILD_DIR) build-fuzz build-asan build-tsan out
