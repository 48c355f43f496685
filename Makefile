# rotorguard: the two commands a fresh machine needs are `make demo` and `make test`.
BUILD_DIR ?= build
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
ROTORGUARD_WARNINGS_AS_ERRORS ?= OFF
# ROS 1 (docs/ros.md): install-deps installs it, so `make` builds with it and its tests run;
# ROTORGUARD_ROS=OFF leaves it out.
ROTORGUARD_ROS ?= ON
DEMO_SCENARIO ?= configs/scenarios/forest.yaml
DEMO_OUT ?= out/demo

.PHONY: all deps configure build demo test bench results peers sanitize fuzz clean

all: build

deps:
	@./scripts/install-deps.sh

configure: deps
	@mkdir -p $(BUILD_DIR)
	@cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release \
	  -DROTORGUARD_WARNINGS_AS_ERRORS=$(ROTORGUARD_WARNINGS_AS_ERRORS) -DROTORGUARD_ROS=$(ROTORGUARD_ROS) \
	  > $(BUILD_DIR)/configure.log 2>&1 \
	  || (cat $(BUILD_DIR)/configure.log; exit 1)

build: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS)

demo: build
	./$(BUILD_DIR)/bin/rotorguard run $(DEMO_SCENARIO) --out $(DEMO_OUT)

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

# The peers of docs/performance.md (HPIPM, GCOPTER's L-BFGS, KISS-ICP), cloned and built outside the sources
# (PEERS_DIR), and the drivers of benchmarks/peers/ that run them beside rotorguard's solvers.
PEERS_DIR ?= out/peers
peers: configure
	@./scripts/install-deps.sh --peers
	./scripts/peers.sh $(PEERS_DIR)
	@cmake -S . -B $(BUILD_DIR) -DROTORGUARD_PEERS_DIR=$(abspath $(PEERS_DIR)) > $(BUILD_DIR)/configure.log 2>&1 \
	  || (cat $(BUILD_DIR)/configure.log; exit 1)
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target peer_qp peer_lbfgs peer_lio rotorguard_cli

# The unit tests under AddressSanitizer and UndefinedBehaviorSanitizer, in their own build folder
# (docs/reliability.md): its build alone takes longer than all of `make test`, so it runs before a
# release rather than in CI.
SANITIZE_DIR ?= build-sanitize
sanitize: deps
	@mkdir -p $(SANITIZE_DIR)
	@cmake -S . -B $(SANITIZE_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DROTORGUARD_SANITIZERS=ON \
	  -DROTORGUARD_BUILD_BENCHMARKS=OFF > $(SANITIZE_DIR)/configure.log 2>&1 \
	  || (cat $(SANITIZE_DIR)/configure.log; exit 1)
	@cmake --build $(SANITIZE_DIR) -j $(JOBS)
	cd $(SANITIZE_DIR) && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --output-on-failure -j $(JOBS)

# Coverage-guided fuzzing of every input file's reader with libFuzzer under AddressSanitizer and
# UndefinedBehaviorSanitizer (clang, in its own build folder; docs/reliability.md), FUZZ_SECONDS
# per target; its corpora grow in $(FUZZ_DIR)/corpus. `make test` runs the targets briefly without
# clang.
FUZZ_DIR ?= build-fuzz
FUZZ_SECONDS ?= 60
fuzz:
	@./scripts/install-deps.sh --fuzz
	@mkdir -p $(FUZZ_DIR)
	@cmake -S . -B $(FUZZ_DIR) -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo -DROTORGUARD_FUZZ=ON \
	  -DROTORGUARD_SANITIZERS=ON -DROTORGUARD_BUILD_BENCHMARKS=OFF -DROTORGUARD_BUILD_EXAMPLES=OFF \
	  > $(FUZZ_DIR)/configure.log 2>&1 || (cat $(FUZZ_DIR)/configure.log; exit 1)
	@cmake --build $(FUZZ_DIR) --target rotorguard_libfuzzer -j $(JOBS)
	./scripts/fuzz.sh $(FUZZ_DIR) $(FUZZ_SECONDS)

bench: build
	./$(BUILD_DIR)/bin/rotorguard bench sim --json

# The published benchmarks -> docs/results.md and README's results block (scripts/results.py;
# finished jobs in out/results are kept, an interrupted one resumes).
results: build
	python3 scripts/results.py --build $(BUILD_DIR) --pack

clean:
	rm -rf $(BUILD_DIR)
