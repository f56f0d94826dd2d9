# A thin wrapper around CMake: the two commands of the README's Quick start.
#   make demo   install what is missing, build, run the main job on the default mesh
#   make check  install what is missing, build, run the whole test suite
BUILD ?= build
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
FUZZ_SECONDS ?= 300
FUZZ ?=
CMAKE_FLAGS ?=

.PHONY: all deps configure build demo check check-asan asan-build fuzz bench thesis table predict install clean

all: build

deps:
	@scripts/deps.sh

configure: deps
	@cmake -S . -B $(BUILD) $(CMAKE_FLAGS) >/dev/null

# CMake's own makefiles run as sub-makes of this one would announce every
# directory they enter ("gmake[3]: Entering directory"): they start as a
# top-level make instead.
build: configure
	@env -u MAKELEVEL -u MAKEFLAGS -u MFLAGS cmake --build $(BUILD) -j $(JOBS)

demo: build
	@scripts/demo.sh $(BUILD)

# After the run, pass or fail, its ten slowest tests (scripts/slowest.sh).
check: build
	@cd $(BUILD) && ctest --output-on-failure -j $(JOBS); rc=$$?; \
	  cd $(CURDIR) && scripts/slowest.sh $(BUILD); exit $$rc

# The test suite again, built with clang under AddressSanitizer and
# UndefinedBehaviorSanitizer, with the fuzz harnesses
# replaying their corpora and regression files (tests/fuzz).
asan-build: deps
	@CC=clang CXX=clang++ cmake -S . -B build-asan -DEMM_SANITIZE=address,undefined >/dev/null
	@env -u MAKELEVEL -u MAKEFLAGS -u MFLAGS cmake --build build-asan -j $(JOBS)

check-asan: asan-build
	@cd build-asan && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
	  ctest --output-on-failure -j $(JOBS); rc=$$?; \
	  cd $(CURDIR) && scripts/slowest.sh build-asan; exit $$rc

# Each libFuzzer harness of tests/fuzz for FUZZ_SECONDS (default 300), one
# after the other (FUZZ="trace din" picks some), in the sanitizer build.
fuzz: asan-build
	@scripts/fuzz.sh build-asan $(FUZZ_SECONDS) $(FUZZ)

bench: build
	@scripts/bench.sh $(BUILD)

# The reproduction of the thesis' chapter 6: tables of Figs. 6.1-6.9, a verdict
# per claim of docs/design.md "What the thesis reports, and what emm
# reproduces", figures, and the
# calibration of compute.per_access (docs/calibration.md). A report, not a test.
thesis: build
	@bench/thesis --calibrate $(BUILD)

# The shipped strategy table, data/table.txt: canonical patterns and the
# example workloads' own profiles (docs/profile.md). Deterministic but for
# ASLR's ~0.1% on the cache baseline; rerun when the features, the machine's
# defaults or the generator change.
table: build
	@scripts/table.sh $(BUILD) data/table.txt

# The prediction benchmark (docs/profile.md "The prediction benchmark"): the
# window's prediction against the whole run's best over a corpus of program
# traces, leave-one-program-out. The traces and replay listings are kept in
# $(BUILD)/bench/predict, so a rerun takes only the decisions. A report, not a test.
predict: build
	@bench/predict.sh $(BUILD)

install: build
	@cmake --install $(BUILD)

clean:
	@rm -rf $(BUILD) build-asan
