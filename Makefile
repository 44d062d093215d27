# ponyhop: the two commands of the README's quick start, and a few for developers.
#   make demo   installs what is missing, builds, renders the demo scenes into out/demo/
#   make test   installs what is missing, builds, runs every test
# CI (.ci/run) runs `make format-check`, `make test`, `make test-asan` (the same tests built with
# ASan+UBSan by clang), `make test-tsan` and a bounded `make fuzz` (in the tree of test-asan).
BUILD      ?= build
ASAN_BUILD ?= build-asan
TSAN_BUILD ?= build-tsan
FUZZ_SECONDS ?= 60
SOAK_SECONDS ?= 600
JOBS       ?= $(shell nproc)
PONYHOP    := $(BUILD)/ponyhop
DEMO_SCENES ?= ponytail ponytail_toss pigtails hair_loop long_hair rope hopper hopper_fall hopper_terrain
DEMO_FRAMES ?= 300
# The rope draws 1024 links a frame (about 0.3 s a frame at the default size, video included): its
# first 1.5 s, the release and the first swing. Later its 64 moving joints let it kink at the rigid
# stretches' ends sooner than the full simulation, which coils too from about 2.5 s (a chain of
# 1 mm links has no bending stiffness).
DEMO_FRAMES_rope ?= 45

PREFIX     ?= /usr/local

.PHONY: all setup build install demo test test-asan test-tsan release fuzz soak format format-check update-snapshots bench bench-quick clean

all: build

setup:
	@bash scripts/setup.sh

# The normal build is the one users make: Release (GCC -O3, warnings as errors), so `make test`
# checks the optimized code and CI needs no second build for -O3's own warnings. Ninja when it is
# there (scripts/setup.sh installs it) for a new build folder; an existing one keeps its generator.
GENERATOR = $(if $(wildcard $(1)/CMakeCache.txt),,$(if $(shell command -v ninja),-G Ninja))
build: setup
	@cmake -S . -B $(BUILD) $(call GENERATOR,$(BUILD)) -DCMAKE_BUILD_TYPE=Release >/dev/null
	@cmake --build $(BUILD) -j$(JOBS)

# The executable, its assets and docs under PREFIX (bin/, share/ponyhop/, share/doc/ponyhop/).
install: build
	@cmake --install $(BUILD) --prefix $(PREFIX)

demo: build
	@for s in $(DEMO_SCENES); do \
	  frames=$(DEMO_FRAMES); [ $$s = rope ] && frames=$(DEMO_FRAMES_rope); \
	  if [ -f assets/scenes/$$s.json ]; then \
	    $(PONYHOP) render assets/scenes/$$s.json --frames $$frames --out out/demo/$$s --video out/demo/$$s.mp4 || exit 1; \
	    echo "demo: frames in out/demo/$$s/, video out/demo/$$s.mp4"; \
	  fi; \
	done
	@echo "demo: the executable is $(PONYHOP) (make install PREFIX=... puts it in PREFIX/bin)"

# Every test, with the normal build (4.4-6 min from a fresh clone on 2 cores by the hour, under a minute of it tests).
test: build
	@cd $(BUILD) && ctest --output-on-failure -j$(JOBS)

# The same tests under AddressSanitizer + UndefinedBehaviorSanitizer, in their own build by clang
# (which compiles instrumented code in about half GCC's time), with the libFuzzer targets of `make fuzz`
# in the same tree: CI runs it after `make test` (its tests about 4 min on 2 cores, session 29: the
# sanitizer tree forces Eigen's small functions inline and long tests measure a shorter stretch
# there, docs/DEVELOPING.md). A tree of this name configured by GCC before
# (sessions before 17) is removed first: naming clang on the command line makes CMake drop the old
# cache, but the re-run then stops at PONYHOP_FUZZ's compiler check.
CLANG_TREE = @if [ -f $(1)/CMakeCache.txt ] && ! grep -q '^CMAKE_CXX_COMPILER:[A-Z]*=.*clang' $(1)/CMakeCache.txt; then \
  echo "$(1): configured by another compiler, removed (clang builds it)"; rm -rf $(1); fi
SANITIZE_CONFIGURE = cmake -S . -B $(ASAN_BUILD) $(call GENERATOR,$(ASAN_BUILD)) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DPONYHOP_FUZZ=ON >/dev/null
test-asan: setup
	@bash scripts/setup.sh --clang
	$(call CLANG_TREE,$(ASAN_BUILD))
	@$(SANITIZE_CONFIGURE)
	@cmake --build $(ASAN_BUILD) -j$(JOBS)
	@# Leak checking is off: llvmpipe/LLVM keep process-lifetime caches that LSan reports as leaks.
	@cd $(ASAN_BUILD) && \
	  ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 \
	  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --output-on-failure -j$(JOBS)

# The tests that run threads (the frame writer's encoder threads, renders with signals and locks)
# under ThreadSanitizer, in their own build (clang, as for ASan) of only what they need.
TSAN_TESTS := engine_tests app_tests
test-tsan: setup
	@bash scripts/setup.sh --clang
	$(call CLANG_TREE,$(TSAN_BUILD))
	@cmake -S . -B $(TSAN_BUILD) $(call GENERATOR,$(TSAN_BUILD)) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DPONYHOP_TSAN=ON -DPONYHOP_WINDOW=OFF >/dev/null
	@cmake --build $(TSAN_BUILD) -j$(JOBS) --target ponyhop $(TSAN_TESTS)
	@cd $(TSAN_BUILD) && TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1:suppressions=$(CURDIR)/tests/tsan.supp \
	  ctest --output-on-failure -j$(JOBS) -R '^(FrameWriter|Video|RenderCommand|OutputSafety)\.' -E 'FullDisk'
# (The full-disk test is left out here: under RLIMIT_FSIZE the TSan runtime's own writes die with
# SIGBUS before ponyhop's error path runs; it runs in make test and make test-asan.)

# What a user gets from a plain `cmake -DCMAKE_BUILD_TYPE=Release` (GCC at -O3, warnings as
# errors): it must build. That is the normal build now, so this is `make build`.
release: build

# The libFuzzer targets of fuzz/ (clang, ASan + UBSan, built in the tree of test-asan), each for
# FUZZ_SECONDS, starting from the seed corpus in fuzz/corpus/NAME and the regression inputs in
# fuzz/regressions/NAME (when a target has any: libFuzzer stops on a folder that does not exist,
# and git keeps no empty one); new inputs go to $(ASAN_BUILD)/corpus/NAME, a crash to
# $(ASAN_BUILD)/crash-* (copy it into fuzz/regressions/NAME once fixed). docs/RELIABILITY.md.
FUZZ_TARGETS := scene clip png mesh
fuzz:
	@bash scripts/setup.sh --clang
	$(call CLANG_TREE,$(ASAN_BUILD))
	@$(SANITIZE_CONFIGURE)
	@cmake --build $(ASAN_BUILD) -j$(JOBS) --target $(addprefix fuzz_,$(FUZZ_TARGETS))
	@for t in $(FUZZ_TARGETS); do \
	  mkdir -p $(ASAN_BUILD)/corpus/$$t; \
	  echo "fuzz: $$t for $(FUZZ_SECONDS) s"; \
	  ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  $(ASAN_BUILD)/fuzz/fuzz_$$t $(ASAN_BUILD)/corpus/$$t fuzz/corpus/$$t $$(ls -d fuzz/regressions/$$t 2>/dev/null) \
	    -max_total_time=$(FUZZ_SECONDS) -max_len=65536 -timeout=30 -rss_limit_mb=3072 \
	    -artifact_prefix=$(ASAN_BUILD)/ -print_final_stats=1 2>$(ASAN_BUILD)/fuzz_$$t.log \
	    || { tail -50 $(ASAN_BUILD)/fuzz_$$t.log; exit 1; }; \
	  grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb|cov: " $(ASAN_BUILD)/fuzz_$$t.log | tail -3; \
	done

# Long runs stay bounded: every shipped scene simulated for SOAK_SECONDS of wall time, max RSS
# printed at 1 and 10 minutes (scripts/soak.sh); and the default method's energy over 60 s of the
# 8-link chain at dt 1/60, 1/240 and 1/1920 (about 4 s of CPU: too long for `make test`, which runs
# 20 s at 1/60 and 60 s at 1/240).
soak: build
	@$(BUILD)/tests/physics_tests --gtest_also_run_disabled_tests \
	  --gtest_filter='PhysicsIntegrator.DISABLED_DefaultMethodHoldsEnergyOver60s'
	@bash scripts/soak.sh $(PONYHOP) $(SOAK_SECONDS)

# The code follows .clang-format (Debian's clang-format): `make format` rewrites every tracked C++
# file in place, `make format-check` (run by CI) lists the files that differ and fails.
FORMAT_FILES = $(shell git ls-files '*.cpp' '*.h')
format:
	@clang-format -i $(FORMAT_FILES)
format-check:
	@command -v clang-format >/dev/null || bash scripts/setup.sh --format
	@bad=$$(for f in $(FORMAT_FILES); do clang-format --dry-run -Werror "$$f" >/dev/null 2>&1 || echo "$$f"; done); 	  if [ -n "$$bad" ]; then echo "format-check: not formatted (run make format):"; echo "$$bad"; exit 1; fi; 	  echo "format-check: $(words $(FORMAT_FILES)) files follow .clang-format"

# Re-render every golden image and physics fingerprint on purpose (never done by tests or CI).
update-snapshots: build
	@$(PONYHOP) snapshot tests/snapshots/shots.txt --update
	@PONYHOP_UPDATE_SNAPSHOTS=1 $(BUILD)/tests/app_tests --gtest_filter='Scenes/Fingerprint.*'
	@echo "goldens rewritten in tests/snapshots/: review them with git diff before committing"

# The report in docs/bench/ (about 20 min on 2 cores), with the peer engines installed first
# (setup.sh --bench: MuJoCo, Bullet, ODE, DART): the whole grid with 10 s long runs, then
# the fixed-anchor chains at dt = 1/240 s for 60 s (energy drift). `ponyhop bench` alone runs 60 s
# long runs on the whole grid (about an hour).
bench:
	@bash scripts/setup.sh --bench
	@$(MAKE) --no-print-directory build
	@$(PONYHOP) bench --out docs/bench --long-fixed 10 --long-shake 5 --long-hopper 5
	@$(PONYHOP) bench --out docs/bench/long60 --links 8,32 --anchors fixed --dts 240 --long-fixed 60 --no-hopper --no-scaling

bench-quick: build
	@$(PONYHOP) bench --quick --out $(BUILD)/bench-quick

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) $(TSAN_BUILD)
