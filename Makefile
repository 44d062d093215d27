# ponyhop: the two commands of the README's quick start, and a few for developers.
#   make demo   installs what is missing, builds, renders the demo scenes into out/demo/
#   make test   installs what is missing, builds, runs every test
# CI (.ci/run) runs `make test`, then `make test-asan`: the same tests built with ASan+UBSan.
BUILD      ?= build
ASAN_BUILD ?= build-asan
JOBS       ?= $(shell nproc)
PONYHOP    := $(BUILD)/ponyhop
DEMO_SCENES ?= ponytail hopper
DEMO_FRAMES ?= 300

.PHONY: all setup build demo test test-asan update-snapshots bench bench-quick clean

all: build

setup:
	@bash scripts/setup.sh

build: setup
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
	@cmake --build $(BUILD) -j$(JOBS)

demo: build
	@for s in $(DEMO_SCENES); do \
	  if [ -f assets/scenes/$$s.json ]; then \
	    $(PONYHOP) render assets/scenes/$$s.json --frames $(DEMO_FRAMES) --out out/demo/$$s --video out/demo/$$s.mp4 || exit 1; \
	    echo "demo: frames in out/demo/$$s/, video out/demo/$$s.mp4"; \
	  fi; \
	done

# Every test, with the normal build (about 5 min from a fresh clone on 2 cores, 30 s of it tests).
test: build
	@cd $(BUILD) && ctest --output-on-failure -j$(JOBS)

# The same tests under AddressSanitizer + UndefinedBehaviorSanitizer, in their own build (about
# 10 min to build and 6 min to run on 2 cores): CI runs it after `make test`.

test-asan: setup
	@cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPONYHOP_SANITIZE=ON >/dev/null
	@cmake --build $(ASAN_BUILD) -j$(JOBS)
	@# Leak checking is off: llvmpipe/LLVM keep process-lifetime caches that LSan reports as leaks.
	@cd $(ASAN_BUILD) && \
	  ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 \
	  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --output-on-failure -j$(JOBS)

# Re-render every golden image and physics fingerprint on purpose (never done by tests or CI).
update-snapshots: build
	@PONYHOP_UPDATE_SNAPSHOTS=1 $(BUILD)/tests/snapshot_test
	@echo "goldens rewritten in tests/snapshots/: review them with git diff before committing"

# The report in docs/bench/ (about 20 min on 2 cores), with the peer engines installed first
# (setup.sh --bench: MuJoCo, Bullet, ODE, DART): the whole grid with 10 s long runs, then
# the fixed-anchor chains at dt = 1/240 s for 60 s (energy drift). `ponyhop bench` alone runs 60 s
# long runs on the whole grid (about an hour).
bench:
	@bash scripts/setup.sh --bench
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
	@cmake --build $(BUILD) -j$(JOBS)
	@$(PONYHOP) bench --out docs/bench --long-fixed 10 --long-shake 5 --long-hopper 5
	@$(PONYHOP) bench --out docs/bench/long60 --links 8,32 --anchors fixed --dts 240 --long-fixed 60 --no-hopper --no-scaling

bench-quick: build
	@$(PONYHOP) bench --quick --out $(BUILD)/bench-quick

clean:
	rm -rf $(BUILD) $(ASAN_BUILD)
