# rtcl: an OpenCL ray tracer for studying load balancing.
#
#   make              build ./rtcl (OIIO=0: without OpenImageIO, .ppm/.pfm only)
#   make deps         install the dependencies (Debian/Ubuntu, uses apt-get)
#   make render       build and render the default scene to render.png
#   make test         unit, kernel (PoCL), command-line and tools tests
#   make experiments  the paper's Table 1 and Figures 6-7 (DEVICE="-p N -d M")
#   make clean
#
# Variables: OIIO=0|1, BUILD (object folder), BIN (the program), CC, CXX, PYTHON (default /usr/bin/python3, Debian's, which
# has numpy, matplotlib and pytest from `make deps`).

OIIO ?= 1
CC ?= gcc
CXX ?= g++
PYTHON ?= /usr/bin/python3
BUILD ?= build
BIN ?= rtcl

WARNINGS := -Wall -Wextra
CPPFLAGS += -I$(BUILD) -Ihost -Icl -DCL_TARGET_OPENCL_VERSION=120 -D_DEFAULT_SOURCE
CFLAGS ?= -O2 -g
CFLAGS += -std=c11 $(WARNINGS)
CXXFLAGS ?= -O2 -g
CXXFLAGS += -std=c++17 $(WARNINGS)
LDLIBS = -lOpenCL -ljansson -lm

ifeq ($(OIIO),1)
IMAGE_BACKEND := $(BUILD)/image_oiio.o
# Expanded when used, so that `make deps render` finds what deps installed.
OIIO_CFLAGS = $(shell pkg-config --cflags OpenImageIO 2>/dev/null)
OIIO_LIBS = $(shell pkg-config --libs OpenImageIO 2>/dev/null)
LDLIBS += $(OIIO_LIBS)
else
IMAGE_BACKEND := $(BUILD)/image_ppm.o
endif
LDLIBS += -lstdc++

# Every host module but main; tests link them too.
HOST_OBJS := $(addprefix $(BUILD)/, cli.o clerror.o device.o devscene.o render.o scene.o \
	stats.o outfile.o workmap.o image_common.o reference.o embedded.o) \
	$(IMAGE_BACKEND)
CL_SOURCES := cl/rtcl_shared.h cl/tracer.cl $(filter-out cl/tracer.cl,$(wildcard cl/*.cl))
EMBEDDED := $(CL_SOURCES) scenes/paper60.json

UNIT_TESTS := $(wildcard test/test_*.c)

.PHONY: all deps render test experiments clean
all: $(BIN)

$(BIN): $(BUILD)/main.o $(HOST_OBJS)
	$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS)

$(BUILD)/embedded.c: tools/embed.py $(EMBEDDED) | $(BUILD)
	$(PYTHON) tools/embed.py $@ $(EMBEDDED)

$(BUILD)/%.o: host/%.c | $(BUILD)
	$(CC) $(CPPFLAGS) $(CFLAGS) -MMD -c -o $@ $<

$(BUILD)/embedded.o: $(BUILD)/embedded.c
	$(CC) $(CPPFLAGS) $(CFLAGS) -c -o $@ $<

$(BUILD)/%.o: host/%.cpp | $(BUILD)
	$(CXX) $(CPPFLAGS) $(CXXFLAGS) $(OIIO_CFLAGS) -MMD -c -o $@ $<

$(BUILD)/test/%.o: test/%.c | $(BUILD)/test
	$(CC) $(CPPFLAGS) $(CFLAGS) -MMD -c -o $@ $<

$(BUILD)/unit_tests: $(UNIT_TESTS:test/%.c=$(BUILD)/test/%.o) $(HOST_OBJS)
	$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS) -lcriterion

$(BUILD) $(BUILD)/test:
	mkdir -p $@

deps:
	bash .ci/install-deps

render: rtcl
	./rtcl

# Criterion first (unit and kernel tests), then pytest (command line and
# tools); pytest's summary line closes the output.
test: rtcl $(BUILD)/unit_tests
	$(BUILD)/unit_tests --jobs 2
	$(PYTHON) -m pytest -q test

# The paper's experiment (Table 1, Figures 6-7) on one device, e.g.
# make experiments DEVICE="-p 1 -d 0"; results under docs/results/<device>/.
experiments: $(BIN)
	$(PYTHON) tools/experiments.py --rtcl ./$(BIN) $(DEVICE)

clean:
	rm -rf $(BUILD) rtcl

-include $(wildcard $(BUILD)/*.d $(BUILD)/test/*.d)
