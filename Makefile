# rtcl: an OpenCL ray tracer for studying load balancing.
#
#   make              build ./rtcl (OIIO=0: without OpenImageIO, .ppm/.pfm/.png only)
#   make deps         install the dependencies (Debian/Ubuntu, uses apt-get)
#   make render       build and render the default scene to render.png
#   make test         unit, kernel (PoCL), command-line and tools tests (<= 3 min)
#   make test-long    the long tests make test leaves out; make check: both
#   make layers       check host/'s layering rule (docs/STYLE.md, "Layers")
#   make test SAN=1   the same suite, host side built with ASan+UBSan in build-san/
#   make fuzz         libFuzzer on the scene loader for FUZZ_SECONDS (needs clang)
#   make fuzz-mesh    the same on mesh files (OBJ, PLY) through Assimp
#   make valgrind     memcheck on full renders (test/valgrind.sh)
#   make experiments  the paper's Table 1 and Figures 6-7 (DEVICE="-p N -d M"), into a
#                     new folder rtcl-results/<device>-<date-time> (OUT=DIR: there)
#   make bench        every kernel over work-group shapes, group counts and batches
#                     (DEVICE="-p N -d M", BENCH="more tools/bench.py options"), the same
#   make results      regenerate the committed docs/results/<device> deliberately:
#                     experiments and bench with --update-committed (the only way a
#                     tool replaces a file tracked by git; review with git diff)
#   make bench-scenes the benchmark scenes (SPD balls, tetra, mount, random balls,
#                     assimp-testmodels, the 2 M-triangle lake) in build/bench-scenes/
#   make install      the built rtcl, its man page, the tools (as rtcl-genscene,
#                     rtcl-bench, ...) and the scenes under DESTDIR/PREFIX
#                     (the tools alone, into any Python: pip install ./tools)
#   make uninstall    remove exactly what install put there
#   make clean
#
# Variables: OIIO=0|1, MPI=0|1 (default: 1 when Open MPI's ompi-c is installed), BUILD (object folder), BIN (the program), CC, CXX, PYTHON (default /usr/bin/python3, Debian's, which
# has numpy, matplotlib and pytest from `make deps`; the installed tools run with it), SAN=1 (sanitizers),
# FUZZ_SECONDS (default 60), FUZZ_CC (default clang), PREFIX (default /usr/local),
# DESTDIR (staging root for packaging, default empty), DEVICE, BENCH and OUT (experiments,
# bench, results: the device options, more bench options, the results folder), OIDN_DIR
# (default /usr/local/lib/rtcl-oidn: where make deps puts Open Image Denoise, and where
# --denoise loads it from).

OIIO ?= 1
CC ?= gcc
CXX ?= g++
PYTHON ?= /usr/bin/python3
SAN ?= 0
ifeq ($(SAN),1)
# A separate tree, so that sanitized and plain objects never mix.
BUILD ?= build-san
BIN ?= $(BUILD)/rtcl
else
BUILD ?= build
BIN ?= rtcl
endif

WARNINGS := -Wall -Wextra
CPPFLAGS += -I$(BUILD) -Ihost -Icl -DCL_TARGET_OPENCL_VERSION=120 -D_DEFAULT_SOURCE
CFLAGS ?= -O2 -g
CFLAGS += -std=c11 $(WARNINGS) -pthread
CXXFLAGS ?= -O2 -g
CXXFLAGS += -std=c++17 $(WARNINGS)
# Mesh files (docs/SCENE.md version 2) through the Open Asset Import Library,
# which only the mesh import helper rtcl-meshread links (host/scene/mesh.h says why).
# Expanded when used, like OIIO_LIBS below.
# Textures are decoded in the helper by stb_image (Debian's libstb-dev, `make deps`):
# its header is compiled into rtcl-meshread (host/meshread/texture_read.c), so the
# OIIO=0 build needs no image library at run time. The helper links jansson too, for
# a glTF file's JSON (host/meshread/gltf_read.c).
ASSIMP_CFLAGS = $(shell pkg-config --cflags assimp 2>/dev/null)
ASSIMP_LIBS = $(shell pkg-config --libs assimp 2>/dev/null || echo -lassimp)
LDLIBS = -lOpenCL -ljansson -lz -lm -pthread -ldl
# --denoise loads Intel Open Image Denoise from here at run time (host/output/denoise.c):
# .ci/install-deps (make deps) installs the pyoidn wheel, which carries it, into this folder.
OIDN_DIR ?= /usr/local/lib/rtcl-oidn
CFLAGS += -DRTCL_OIDN_DIR='"$(OIDN_DIR)"'
MESHREAD := $(BUILD)/rtcl-meshread
RAYS := $(BUILD)/rtcl-rays

ifeq ($(SAN),1)
SAN_FLAGS := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all
CFLAGS += $(SAN_FLAGS)
CXXFLAGS += $(SAN_FLAGS)
LDFLAGS += $(SAN_FLAGS)
# Every report is fatal, also in Criterion's forked workers. LeakSanitizer
# skips only the OpenCL runtime's own allocations (test/lsan.supp says which).
export ASAN_OPTIONS := abort_on_error=1:halt_on_error=1:detect_leaks=1:strict_string_checks=1:check_initialization_order=1
export UBSAN_OPTIONS := print_stacktrace=1:halt_on_error=1:abort_on_error=1
export LSAN_OPTIONS := suppressions=$(CURDIR)/test/lsan.supp:print_suppressions=0
endif

ifeq ($(OIIO),1)
# OpenImageIO's backend is a module that rtcl loads only for the formats it
# does not write itself (host/output/image_dl.c says why).
IMAGE_BACKEND := $(BUILD)/output/image_dl.o
OIIO_MODULE := $(BUILD)/rtcl-oiio.so
LDLIBS += -ldl
# Expanded when used, so that `make deps render` finds what deps installed.
OIIO_CFLAGS = $(shell pkg-config --cflags OpenImageIO 2>/dev/null)
OIIO_LIBS = $(shell pkg-config --libs OpenImageIO 2>/dev/null)
else
IMAGE_BACKEND := $(BUILD)/output/image_ppm.o
endif
LDLIBS += -lstdc++

# MPI=1: --mpi through Open MPI (host/run/mpi_render.c); MPI=0: host/run/mpi_stub.c,
# whose --mpi says how to get it. The default: 1 when Open MPI is installed.
MPI ?= $(shell pkg-config --exists ompi-c 2>/dev/null && echo 1 || echo 0)
ifeq ($(MPI),1)
MPI_MODULE := $(BUILD)/run/mpi_render.o
MPI_CFLAGS = $(shell pkg-config --cflags ompi-c)
LDLIBS += $(shell pkg-config --libs ompi-c)
else
MPI_MODULE := $(BUILD)/run/mpi_stub.o
endif

# Every host module but main, by folder (host/README.md: the layers); tests
# link them too. Objects mirror the folders: build/render/launch.o.
HOST_MODULES := \
	base/timing base/files base/test_hooks base/quote base/suggest base/interrupt base/libdir base/progress \
	scene/scene scene/scene_check scene/scene_literal scene/scene_material scene/scene_mesh \
	scene/mesh_place scene/mesh_spawn scene/scene_model scene/hdr_read \
	device/device device/devices device/clerror device/progcache \
	layout/bvh layout/mesh_block layout/scene_block \
	render/checks render/probe render/buffers render/program render/block render/watch render/repeats \
	render/launch render/singlepass render/wavefront render/stages render/renderer render/render render/aov \
	render/reference render/reference_scene render/reference_path \
	schedule/dispenser schedule/multidev schedule/adapt schedule/tiles \
	job/job job/record \
	report/summary report/document report/simd report/devstats \
	output/plan output/npy output/schedmap output/workmap output/image_common output/image_encode \
	output/image_png output/denoise \
	run/image run/frames run/job_digest \
	cmd/cli
HOST_OBJS := $(addprefix $(BUILD)/, $(addsuffix .o,$(HOST_MODULES)) embedded.o) \
	$(IMAGE_BACKEND) $(MPI_MODULE)
CL_SOURCES := cl/rtcl_shared.h $(wildcard cl/*.cl)
EMBEDDED := $(CL_SOURCES) scenes/paper60.json

UNIT_TESTS := $(wildcard test/test_*.c)

.PHONY: all deps render test test-long check layers experiments bench results bench-scenes clean fuzz fuzz-mesh valgrind install uninstall
all: $(BIN) $(RAYS)

$(BIN): $(BUILD)/cmd/main.o $(HOST_OBJS) $(OIIO_MODULE) $(MESHREAD)
	$(CC) $(LDFLAGS) -o $@ $(filter %.o,$^) $(LDLIBS)

# rtcl's traversal over rays from a file, timed (host/cmd/rays.c): the
# instrument of rtcl-peer-compare --rays (docs/bvh.md).
$(RAYS): $(BUILD)/cmd/rays.o $(HOST_OBJS) $(MESHREAD)
	$(CC) $(LDFLAGS) -o $@ $(filter %.o,$^) $(LDLIBS)

# The mesh import helper: Assimp in a process of its own.
$(MESHREAD): $(BUILD)/meshread/meshread.o $(BUILD)/meshread/meshread_assimp.o \
		$(BUILD)/meshread/ply_check.o $(BUILD)/meshread/texture_read.o \
		$(BUILD)/meshread/gltf_read.o $(BUILD)/meshread/mtl_read.o $(BUILD)/scene/mesh_spawn.o \
		$(BUILD)/base/libdir.o
	$(CC) $(LDFLAGS) -o $@ $^ $(ASSIMP_LIBS) -ljansson -lstdc++ -lm

# Where the companion files (rtcl-oiio.so, rtcl-meshread) are in a build tree.
$(BUILD)/base/libdir.o: CPPFLAGS += -DRTCL_MODULE_DIR='"$(abspath $(BUILD))"'

$(BUILD)/rtcl-oiio.so: host/output/image_oiio.cpp host/output/image_encode.c | $(BUILD)
	@mkdir -p $(BUILD)/output
	$(CC) $(CPPFLAGS) $(CFLAGS) -fPIC -c -o $(BUILD)/output/image_encode.pic.o host/output/image_encode.c
	$(CXX) $(CPPFLAGS) $(CXXFLAGS) $(OIIO_CFLAGS) -fPIC -shared -MMD -MP -MF $(BUILD)/output/rtcl-oiio.d \
		$(LDFLAGS) -o $@ $< $(BUILD)/output/image_encode.pic.o $(OIIO_LIBS)

$(BUILD)/embedded.c: tools/build/embed.py $(EMBEDDED) | $(BUILD)
	$(PYTHON) tools/build/embed.py $@ $(EMBEDDED)

$(BUILD)/%.o: host/%.c | $(BUILD)
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(CFLAGS) $(ASSIMP_CFLAGS) -MMD -MP -c -o $@ $<

$(BUILD)/run/mpi_render.o: host/run/mpi_render.c | $(BUILD)
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(MPI_CFLAGS) $(CFLAGS) -MMD -MP -c -o $@ $<

$(BUILD)/embedded.o: $(BUILD)/embedded.c
	$(CC) $(CPPFLAGS) $(CFLAGS) -c -o $@ $<

$(BUILD)/%.o: host/%.cpp | $(BUILD)
	@mkdir -p $(@D)
	$(CXX) $(CPPFLAGS) $(CXXFLAGS) $(OIIO_CFLAGS) -MMD -MP -c -o $@ $<

# Objects in tests/, so that the .d files of the flat layout before host/
# had folders are never read (they name headers that moved).
$(BUILD)/tests/%.o: test/%.c | $(BUILD)/tests
	$(CC) $(CPPFLAGS) $(CFLAGS) -MMD -MP -c -o $@ $<

$(BUILD)/unit_tests: $(UNIT_TESTS:test/%.c=$(BUILD)/tests/%.o) $(HOST_OBJS) $(OIIO_MODULE) $(MESHREAD)
	$(CC) $(LDFLAGS) -o $@ $(filter %.o,$^) $(LDLIBS) -lcriterion

$(BUILD) $(BUILD)/tests:
	mkdir -p $@

deps:
	OIDN_DIR='$(OIDN_DIR)' bash .ci/install-deps

render: rtcl
	./rtcl

# The tests: Criterion first (unit and kernel tests), then pytest (command
# line and tools), each on every core (--jobs, pytest-xdist's -n); pytest's
# summary line closes the output, after the time the whole target took.
#   make test       the quick suite: at most 3 minutes on 2 cores from a fresh
#                   clone with cold program caches
#   make test-long  what the quick suite leaves out: Criterion suites named
#                   *_slow and pytest's `slow` marker (long renders, the tools
#                   run end to end, figure redraws, interrupt sweeps)
#   make check      both
# PoCL compiles a program once more for every work-group size it is launched
# with; the quick suite turns that off (POCL_WORK_GROUP_SPECIALIZATION=0), which
# halves its cold-cache time with the same images, and builds without LLVM's
# optimisations (POCL_EXTRA_BUILD_FLAGS=-cl-opt-disable: a program compiles in
# about half the time, and the suite's images are small, so it takes 2:51
# instead of 3:02-3:17 cold on 2 cores at 54a63f2, every test passing either
# way). make test-long keeps PoCL's defaults, so the optimised, specialised
# programs users get are tested too.
TEST_JOBS ?= $(shell nproc)
TEST_START := $(shell date +%s.%N)
QUICK_TEST_ENV := POCL_WORK_GROUP_SPECIALIZATION=0 POCL_EXTRA_BUILD_FLAGS=-cl-opt-disable
PYTEST = RTCL=$(abspath $(BIN)) RTCL_TEST_START=$(TEST_START) $(PYTHON) -m pytest -q -n $(TEST_JOBS)

test: $(BIN) $(RAYS) $(BUILD)/unit_tests
	$(QUICK_TEST_ENV) $(BUILD)/unit_tests --jobs $(TEST_JOBS) --filter '!(*_slow)/*'
	$(QUICK_TEST_ENV) RTCL_TEST_WHAT="make test" $(PYTEST) -m "not slow" test

test-long: $(BIN) $(RAYS) $(BUILD)/unit_tests
	$(BUILD)/unit_tests --jobs $(TEST_JOBS) --filter '*_slow/*'
	RTCL_TEST_WHAT="make test-long" $(PYTEST) -m slow test

check: test test-long

# The layering rule of docs/STYLE.md ("Layers"): includes and, from the
# objects, calls between host/'s folders.
layers: $(BIN)
	$(PYTHON) tools/build/layers.py --objects $(BUILD)

# The paper's experiment (Table 1, Figures 6-7) on one device, e.g.
# make experiments DEVICE="-p 1 -d 0"; results in a new folder
# rtcl-results/<device>-<date-time>, or in OUT=DIR.
OUT_OPTION = $(if $(OUT),-o $(OUT))
experiments: $(BIN)
	$(PYTHON) tools/experiments.py --rtcl ./$(BIN) $(DEVICE) $(OUT_OPTION)

# The benchmark (issue 4): every kernel x work-group shapes x group counts x
# batches, median of 10 launches each, e.g. make bench DEVICE="-p 1 -d 0"
# BENCH="--scaling"; bench.md and bench.csv in a new folder
# rtcl-results/<device>-<date-time>, or in OUT=DIR.
bench: $(BIN)
	$(PYTHON) tools/bench.py --rtcl ./$(BIN) $(DEVICE) $(BENCH) $(OUT_OPTION)

# The committed results of one device, regenerated on purpose: the only target
# that replaces files tracked by git (docs/results/<device>/: results.json,
# table1.md, the figures, bench.md, bench.csv); git diff shows what changed.
results: $(BIN)
	$(PYTHON) tools/experiments.py --rtcl ./$(BIN) $(DEVICE) --update-committed
	$(PYTHON) tools/bench.py --rtcl ./$(BIN) $(DEVICE) $(BENCH) --update-committed

# The benchmark scenes (docs/benchmark-scenes.md), generated, never committed.
BENCH_SCENES ?= build/bench-scenes
bench-scenes:
	$(PYTHON) tools/genbench.py all -o $(BENCH_SCENES)

# libFuzzer on the scene loader and scene_block_pack (test/fuzz_scene.c), seeded
# with the shipped and the bad scenes; the seeds are copied, the growing corpus
# and any crash-*, leak-*, timeout-* files stay under build/fuzz/.
FUZZ_SECONDS ?= 60
FUZZ_CC ?= clang
FUZZ_DIR := build/fuzz
FUZZ_FLAGS := -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
	-fno-omit-frame-pointer -std=c11 $(WARNINGS) -Ihost -Icl -D_DEFAULT_SOURCE

# The scene loader and what it calls: its parts, the file reader, the interrupt
# bookkeeping the file module keeps, and the side of the mesh import that
# starts the helper; the helper (build/fuzz/rtcl-meshread) is built with the
# same sanitizers, and its reports fail the run (host/scene/mesh.h).
FUZZ_SOURCES := host/scene/scene.c host/scene/scene_check.c host/scene/scene_literal.c host/scene/scene_material.c host/base/suggest.c \
	host/scene/scene_mesh.c host/scene/mesh_spawn.c host/base/libdir.c host/scene/mesh_place.c host/scene/hdr_read.c \
	host/base/files.c host/base/quote.c \
	host/base/interrupt.c host/layout/scene_block.c \
	host/layout/mesh_block.c host/layout/bvh.c
FUZZ_HEADERS := test/scene_block_check.h host/scene/scene.h host/scene/scene_loader.h host/scene/mesh.h \
	host/scene/mesh_place.h host/scene/hdr_read.h host/base/files.h host/base/quote.h host/layout/scene_block.h host/layout/mesh_block.h host/layout/bvh.h host/base/libdir.h \
	cl/rtcl_shared.h
FUZZ_MODULE_DIR := -DRTCL_MODULE_DIR='"$(abspath $(FUZZ_DIR))"'

$(FUZZ_DIR)/rtcl-meshread: host/meshread/meshread.c host/meshread/meshread_assimp.c host/meshread/ply_check.c host/meshread/ply_check.h host/meshread/texture_read.c host/meshread/texture_read.h host/meshread/gltf_read.c host/meshread/gltf_read.h host/meshread/mtl_read.c host/meshread/mtl_read.h host/scene/mesh_spawn.c host/base/libdir.c host/scene/mesh.h
	mkdir -p $(FUZZ_DIR)
	$(FUZZ_CC) $(filter-out -fsanitize=fuzzer%,$(FUZZ_FLAGS)) -fsanitize=address,undefined \
		$(FUZZ_MODULE_DIR) -o $@ $(filter %.c,$^) $(ASSIMP_LIBS) -ljansson -lstdc++ -lm

$(FUZZ_DIR)/fuzz_scene: test/fuzz_scene.c $(FUZZ_SOURCES) $(FUZZ_HEADERS) $(FUZZ_DIR)/rtcl-meshread
	$(FUZZ_CC) $(FUZZ_FLAGS) $(FUZZ_MODULE_DIR) -pthread -o $@ test/fuzz_scene.c $(FUZZ_SOURCES) \
		-ljansson -lm

# The same for mesh files (test/fuzz_mesh.c): malformed OBJ and PLY through
# the helper (Assimp), the placement and the packing, seeded from the
# committed meshes and the earlier findings.
$(FUZZ_DIR)/fuzz_mesh: test/fuzz_mesh.c $(FUZZ_SOURCES) $(FUZZ_HEADERS) $(FUZZ_DIR)/rtcl-meshread
	$(FUZZ_CC) $(FUZZ_FLAGS) $(FUZZ_MODULE_DIR) -pthread -o $@ test/fuzz_mesh.c $(FUZZ_SOURCES) \
		-ljansson -lm

fuzz: $(FUZZ_DIR)/fuzz_scene
	mkdir -p $(FUZZ_DIR)/corpus $(FUZZ_DIR)/artifacts
	cp $(filter-out %.md,$(wildcard scenes/*.json test/bad_scenes/*.json \
		test/fuzz_corpus/* test/fuzz_regressions/*)) $(FUZZ_DIR)/corpus/
	$(FUZZ_DIR)/fuzz_scene -max_total_time=$(FUZZ_SECONDS) -max_len=65536 -timeout=10 \
		-rss_limit_mb=2048 -dict=test/fuzz_scene.dict -print_final_stats=1 \
		-artifact_prefix=$(FUZZ_DIR)/artifacts/ $(FUZZ_DIR)/corpus

# Findings go to test/fuzz_mesh_regressions/, replayed by `make test`.
fuzz-mesh: $(FUZZ_DIR)/fuzz_mesh
	mkdir -p $(FUZZ_DIR)/mesh_corpus $(FUZZ_DIR)/artifacts
	cp $(filter-out %.md,$(wildcard test/meshes/*.obj test/meshes/*.ply scenes/models/icosphere.obj \
		test/fuzz_mesh_regressions/* test/fuzz_mesh_materials/*.obj \
		test/fuzz_mesh_materials/*.gltf)) $(FUZZ_DIR)/mesh_corpus/
	$(FUZZ_DIR)/fuzz_mesh -max_total_time=$(FUZZ_SECONDS) -max_len=16384 -timeout=10 \
		-dict=test/fuzz_mesh.dict \
		-rss_limit_mb=2048 -print_final_stats=1 \
		-artifact_prefix=$(FUZZ_DIR)/artifacts/mesh- $(FUZZ_DIR)/mesh_corpus

# Memcheck on full renders; test/valgrind.supp covers the OpenCL runtime only.
valgrind: $(BIN)
	bash test/valgrind.sh $(BIN)

# Install: the program, its man page, the scenes, and the tools: the package
# rtcl_tools in share/rtcl/tools and one command per tools/NAME.py, rtcl-NAME
# (_ as -), which runs the rtcl_tools.commands module that tools/NAME.py imports
# (tools/build/tool_wrapper.py.in; pip install ./tools makes the same commands);
# the man page names the files under PREFIX.
# install depends on the binary, so an up-to-date one is copied as built,
# never rebuilt with other flags.
PREFIX ?= /usr/local
DESTDIR ?=
INSTALL ?= install
BINDIR := $(DESTDIR)$(PREFIX)/bin
MAN1DIR := $(DESTDIR)$(PREFIX)/share/man/man1
LIBDIR := $(DESTDIR)$(PREFIX)/lib/rtcl
DATADIR := $(DESTDIR)$(PREFIX)/share/rtcl
TOOL_SCRIPTS := $(wildcard tools/*.py)
TOOL_MODULES := $(wildcard tools/rtcl_tools/*.py)
# The peer comparison's sources, built on the user's machine against the peer
# (rtcl-peer-compare --counts and --rays).
TOOL_SOURCES := $(wildcard tools/rtcl_tools/*.cpp tools/rtcl_tools/*.cl)
TOOL_COMMAND_MODULES := $(wildcard tools/rtcl_tools/commands/*.py)
TOOL_COMMANDS := $(addprefix rtcl-,$(subst _,-,$(basename $(notdir $(TOOL_SCRIPTS)))))
SCENE_FILES := $(wildcard scenes/*.json) scenes/README.md
# The mesh files the version 2 scenes place, relative to them.
# Every file under scenes/models, its folders kept (models/cornell/...).
SCENE_MODELS := $(sort $(shell find scenes/models -type f))
SCENE_MODEL_DIRS := $(sort $(shell find scenes/models -mindepth 1 -type d))

install: $(BIN) $(RAYS)
	$(INSTALL) -d $(BINDIR) $(MAN1DIR) $(LIBDIR) $(DATADIR)/scenes \
		$(DATADIR)/tools/rtcl_tools/commands
	$(INSTALL) -m 755 $(BIN) $(BINDIR)/rtcl
	$(INSTALL) -m 755 $(MESHREAD) $(RAYS) $(LIBDIR)
	$(if $(OIIO_MODULE),$(INSTALL) -m 644 $(OIIO_MODULE) $(LIBDIR))
	sed -e 's|/usr/local/|$(PREFIX)/|g' docs/rtcl.1 > $(MAN1DIR)/rtcl.1
	chmod 644 $(MAN1DIR)/rtcl.1
	$(INSTALL) -m 644 $(SCENE_FILES) $(DATADIR)/scenes
	$(INSTALL) -d $(DATADIR)/scenes/models $(addprefix $(DATADIR)/,$(SCENE_MODEL_DIRS))
	for file in $(SCENE_MODELS); do \
		$(INSTALL) -m 644 "$$file" "$(DATADIR)/$$file" || exit 1; \
	done
	$(INSTALL) -m 644 $(TOOL_MODULES) $(TOOL_SOURCES) $(DATADIR)/tools/rtcl_tools
	$(INSTALL) -m 644 $(TOOL_COMMAND_MODULES) $(DATADIR)/tools/rtcl_tools/commands
	for script in $(TOOL_SCRIPTS); do \
		command=rtcl-$$(basename $$script .py | tr _ -); \
		module=$$(sed -n 's/^from rtcl_tools\.commands\.\([a-z_]*\) import main\( *#.*\)\{0,1\}$$/\1/p' $$script); \
		[ -n "$$module" ] || { echo "$$script: no rtcl_tools.commands module" >&2; exit 1; }; \
		sed -e "s|@COMMAND@|$$command|g" -e "s|@MODULE@|$$module|g" \
			-e "s|@PYTHON@|$(PYTHON)|g" tools/build/tool_wrapper.py.in \
			> $(BINDIR)/$$command && chmod 755 $(BINDIR)/$$command || exit 1; \
	done

# What install wrote (and the __pycache__ that running the tools with python3
# directly may have left), then the folders it made under share/rtcl, each only
# if nothing else is left in it; bin, share/man and PREFIX stay.
uninstall:
	rm -f $(BINDIR)/rtcl $(addprefix $(BINDIR)/,$(TOOL_COMMANDS)) $(MAN1DIR)/rtcl.1
	rm -f $(LIBDIR)/rtcl-oiio.so $(LIBDIR)/rtcl-meshread $(LIBDIR)/rtcl-rays
	rm -f $(addprefix $(DATADIR)/scenes/,$(notdir $(SCENE_FILES)))
	rm -f $(addprefix $(DATADIR)/,$(SCENE_MODELS))
	rm -f $(addprefix $(DATADIR)/tools/rtcl_tools/,$(notdir $(TOOL_MODULES) $(TOOL_SOURCES)))
	rm -f $(addprefix $(DATADIR)/tools/rtcl_tools/commands/,$(notdir $(TOOL_COMMAND_MODULES)))
	rm -rf $(DATADIR)/tools/__pycache__ $(DATADIR)/tools/rtcl_tools/__pycache__ \
		$(DATADIR)/tools/rtcl_tools/commands/__pycache__
	for dir in $(addprefix $(DATADIR)/,$(SCENE_MODEL_DIRS)) \
			$(DATADIR)/scenes/models $(DATADIR)/scenes $(DATADIR)/tools/rtcl_tools/commands \
			$(DATADIR)/tools/rtcl_tools \
			$(DATADIR)/tools $(DATADIR) $(LIBDIR); do \
		if [ -d $$dir ] && [ -z "$$(ls -A $$dir)" ]; then rmdir $$dir; fi; \
	done

clean:
	rm -rf $(BUILD) build-san build/fuzz rtcl

-include $(wildcard $(BUILD)/*/*.d)
