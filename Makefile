# The newcomer's entry points. Each target installs missing Debian packages,
# configures and builds, then does its job.
BUILD    ?= build
ASAN     ?= build-asan
JOBS     ?= $(shell nproc)
DEPS      = build-essential cmake pkg-config libpng-dev libopenexr-dev zlib1g-dev \
            libcjson-dev libcmocka-dev libcairo2-dev fonts-dejavu-core python3 \
            python3-numpy python3-venv python3-setuptools python3-wheel $(VIEW_DEPS) $(MPI_DEPS) $(GLTF_DEPS)
# gltfpack (meshoptimizer) reads and validates (cgltf) the heal run's .glb in tests
GLTF_DEPS = gltfpack
# MPI for the distributed healing solver and optics table (docs/scaling.md)
MPI_DEPS  = libopenmpi-dev openmpi-bin
# The viewer (skinsim view): GTK 4, libepoxy, Mesa's software OpenGL/EGL, and
# Xvfb so its tests have a display on a machine without one.
VIEW_DEPS = libgtk-4-dev libepoxy-dev libgl1-mesa-dri libegl-mesa0 xvfb
DEMO_OUT ?= demo-out

.PHONY: all deps build demo test test-asan bench fuzz clean install test-blender blender-extension demo-mpi bench-mpi

all: build

deps:
	@missing=""; for p in $(DEPS); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "Installing:$$missing"; \
	  SUDO=""; [ "$$(id -u)" = 0 ] || SUDO=sudo; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing; \
	fi

build: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo $(CMAKE_ARGS) >/dev/null
	cmake --build $(BUILD) -j $(JOBS)

demo: build
	@rm -rf $(DEMO_OUT)
	$(BUILD)/skinsim abrasion --out $(DEMO_OUT)/abrasion
	$(BUILD)/skinsim optics swatch --out $(DEMO_OUT)/skin_swatch.png
	$(BUILD)/skinsim heal --days 21 --out $(DEMO_OUT)/heal
	$(BUILD)/skinsim skin --size 1024 --gltf --out $(DEMO_OUT)/skin
	$(BUILD)/skinsim wound --scenario scab --skin $(DEMO_OUT)/skin --out $(DEMO_OUT)/wound
	$(BUILD)/skinsim wound --heal $(DEMO_OUT)/heal --days 0,3,7,14,21 --out $(DEMO_OUT)/wound-from-heal
	@echo
	@echo "Look at:"
	@echo "  $(DEMO_OUT)/abrasion/contact_sheet.png   abrasion from injury to day 30"
	@echo "  $(DEMO_OUT)/skin_swatch.png              skin colours over melanin x blood"
	@echo "  $(DEMO_OUT)/heal/area.png                wound closure over 21 days"
	@echo "  $(DEMO_OUT)/heal/fields/fields.pvd       open in ParaView"
	@echo "  $(DEMO_OUT)/skin/contact_sheet.png       a patch of forearm skin: every map side by side"
	@echo "  $(DEMO_OUT)/wound/contact_sheet.png      simulated healing as skin, day 0 to 365"
	@echo "  $(DEMO_OUT)/wound-from-heal/contact_sheet.png  the heal run above as skin (wound --heal)"

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

test-asan: deps
	cmake -S . -B $(ASAN) -DCMAKE_BUILD_TYPE=Debug -DSKINSIM_SANITIZE=ON $(CMAKE_ARGS)
	cmake --build $(ASAN) -j $(JOBS)
	cd $(ASAN) && ASAN_OPTIONS=detect_leaks=1 LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp UBSAN_OPTIONS=print_stacktrace=1 SKINSIM_TEST_QUICK=1 \
	  ctest --output-on-failure -j $(JOBS)

# Installs library (shared + static), headers, data, skinsim.pc, the CMake
# package, the command and the Python package under PREFIX.
PREFIX   ?= /usr/local
install: build
	cmake --install $(BUILD) --prefix $(PREFIX)

# The Blender add-on, headless (installs Debian's blender for this target only).
test-blender: build
	@dpkg-query -W -f='$${Status}' blender 2>/dev/null | grep -q "ok installed" || { \
	  SUDO=""; [ "$$(id -u)" = 0 ] || SUDO=sudo; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq blender; }
	cd $(BUILD) && SKINSIM_TEST_BLENDER=1 ctest --output-on-failure -R '^e2e_blender'

# The add-on as a Blender 4.2+ extension (blender_manifest.toml + __init__.py
# zipped; install it from Blender's Preferences > Get Extensions > Install
# from Disk). The legacy add-on is the folder integrations/blender/skinsim_blender.
blender-extension: deps
	@mkdir -p $(BUILD)
	/usr/bin/python3 integrations/blender/build_extension.py $(BUILD)/skinsim_blender-$$(sed -n 's/^version = "\(.*\)"/\1/p' integrations/blender/skinsim_blender/blender_manifest.toml).zip

# The healing solver and the ModelMatch table on 4 MPI ranks (docs/scaling.md).
# OpenMPI refuses to run as root without --allow-run-as-root; --oversubscribe
# lets 4 ranks share fewer cores. Same files, bit for bit, as `make demo`'s heal.
MPIRUN ?= mpirun --allow-run-as-root --oversubscribe
demo-mpi: build
	@rm -rf $(DEMO_OUT)/heal-mpi
	$(MPIRUN) -np 4 $(BUILD)/skinsim heal --days 21 --out $(DEMO_OUT)/heal-mpi
	$(MPIRUN) -np 3 $(BUILD)/skinsim optics table --samples 2 --photons 2000 --out $(DEMO_OUT)/mm-mpi.sstab
	@echo "Look at: $(DEMO_OUT)/heal-mpi/area.png, $(DEMO_OUT)/heal-mpi/fields/fields.pvd"

# Strong and weak scaling of the MPI healing solver (figures in docs/scaling.md).
bench-mpi: build
	bench/heal_mpi.sh $(BUILD) 20 3 1 explicit
	bench/heal_mpi.sh $(BUILD) 10 3 1 split

bench: build
	@for b in $(BUILD)/bench_*; do echo "== $$b"; $$b; done

# Fuzz every input reader with clang's libFuzzer: one target per format
# (tests/fuzz/fuzz_<format>.c), seeded by make_seeds with valid and hostile
# inputs, FUZZ_SECONDS each; FUZZ=png,mci picks targets. Corpora grow in
# build-fuzz/corpus/, crashes land in build-fuzz/crash-* (docs/reliability.md).
FUZZ_SECONDS ?= 60
FUZZ ?= $(patsubst tests/fuzz/fuzz_%.c,%,$(wildcard tests/fuzz/fuzz_*.c))
fuzz: deps
	@command -v clang >/dev/null || { SUDO=""; [ "$$(id -u)" = 0 ] || SUDO=sudo; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq clang; }
	@mkdir -p build-fuzz
	cmake -S tests/fuzz -B build-fuzz -DCMAKE_C_COMPILER=clang >/dev/null
	cmake --build build-fuzz -j $(JOBS)
	build-fuzz/make_seeds build-fuzz/seeds .
	@for t in $(subst $(comma), ,$(FUZZ)); do \
	  mkdir -p build-fuzz/corpus/$$t; echo "== fuzz_$$t, $(FUZZ_SECONDS) s"; \
	  build-fuzz/fuzz_$$t -max_total_time=$(FUZZ_SECONDS) -rss_limit_mb=2048 -timeout=20 \
	    -artifact_prefix=build-fuzz/crash-$$t- build-fuzz/corpus/$$t build-fuzz/seeds/$$t \
	    >build-fuzz/$$t.log 2>&1 || { tail -40 build-fuzz/$$t.log; exit 1; }; \
	  grep DONE build-fuzz/$$t.log | tail -1; \
	done
comma := ,

clean:
	rm -rf $(BUILD) $(ASAN) build-fuzz
