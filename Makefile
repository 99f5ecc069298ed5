# dfle - debris-flow and fluvial landscape evolution, scripted in Lua.
#
#   make            library, CLI (build/dfle) and Lua module (build/dfle.so)
#   make test       every test: cmocka binaries, Lua tests, example smoke runs
#   make check      the same tests built with AddressSanitizer + UBSan
#   make fuzz       the API fuzzer's long mode (50,000 calls) in that build
#                   (tests/fuzz/; a short fixed-seed mode is part of test)
#   make memcheck   the cmocka tests under valgrind
#   make bench      benchmark figures (see bench/; C drivers go to build/bench/)
#   make mpi        build/dfle-mpi, ensembles across MPI ranks (needs mpicc;
#                   `make test-mpi` checks it; doc/ensembles.md)
#   make python     the Python package dfle (build/python/dfle), for Debian's
#                   /usr/bin/python3 with numpy (doc/python.md)
#   make install    PREFIX=/usr/local DESTDIR=
#   make clean
#
# CC=clang works too.  Objects go to $(BUILD) with dependency files.

VERSION   := 0.1.0
CC        ?= cc
MPICC     ?= mpicc
# Debian's interpreter, never another one first on PATH; its headers and
# numpy's.  Without them `make python` fails and the tests skip Python.
# (Set here: the test and bench rules' prerequisites read HAVE_PYTHON.)
PYTHON    ?= /usr/bin/python3
HAVE_PYTHON := $(shell $(PYTHON) -c 'import numpy, sysconfig; sysconfig.get_paths' 2>/dev/null && \
                 test -f "$$($(PYTHON) -c 'import sysconfig; print(sysconfig.get_paths()["include"])')/Python.h" && echo yes)
PKG_CONFIG ?= pkg-config
LUA_PKG   ?= lua5.4
BUILD     ?= build
PREFIX    ?= /usr/local
DESTDIR   ?=

LUA_CFLAGS  ?= $(shell $(PKG_CONFIG) --cflags $(LUA_PKG))
LUA_LIBS    ?= $(shell $(PKG_CONFIG) --libs $(LUA_PKG))
GSL_CFLAGS  ?= $(shell $(PKG_CONFIG) --cflags gsl)
GSL_LIBS    ?= $(shell $(PKG_CONFIG) --libs gsl)
GDAL_CFLAGS ?= $(shell $(PKG_CONFIG) --cflags gdal)
NETCDF_CFLAGS ?= $(shell $(PKG_CONFIG) --cflags netcdf)
NETCDF_LIBS ?= $(shell $(PKG_CONFIG) --libs netcdf)
CMOCKA_CFLAGS ?= $(shell $(PKG_CONFIG) --cflags cmocka)
CMOCKA_LIBS ?= $(shell $(PKG_CONFIG) --libs cmocka)
# dlopen: in libc since glibc 2.34 (Debian 12); -ldl on older systems.
DL_LIBS   ?=

OPT       ?= -O2
WARN      := -Wall -Wextra -Werror -Wshadow -Wstrict-prototypes -Wmissing-prototypes
CFLAGS    ?= $(OPT) -g
ALL_CFLAGS := -std=c11 -D_POSIX_C_SOURCE=200809L -fPIC -pthread $(WARN) $(CFLAGS) $(SANITIZE) \
              -Iinclude -DDFLE_VERSION='"$(VERSION)"'
ALL_LDFLAGS := $(LDFLAGS) $(SANITIZE) -pthread

# The tree reads like the architecture (README "Layout"): the C library is
# every folder of src/ but the Lua binding, the command and the MPI driver.
CORE_SRC  := $(filter-out src/lua/% src/cli/% src/mpi/% src/python/%,$(wildcard src/*/*.c))
LUA_SRC   := $(wildcard src/lua/*/*.c)
CLI_SRC   := $(wildcard src/cli/*.c)
TEST_SRC  := $(wildcard tests/test_*.c)
BENCH_SRC := $(wildcard bench/*.c)

CORE_OBJ  := $(CORE_SRC:%.c=$(BUILD)/obj/%.o)
LUA_OBJ   := $(LUA_SRC:%.c=$(BUILD)/obj/%.o)
CLI_OBJ   := $(CLI_SRC:%.c=$(BUILD)/obj/%.o)
TEST_BIN  := $(TEST_SRC:tests/%.c=$(BUILD)/tests/%)
BENCH_BIN := $(BENCH_SRC:bench/%.c=$(BUILD)/bench/%)

LIB_CORE  := $(BUILD)/libdfle.a
# GDAL and libnetcdf are not linked: the library loads them on first use
# (src/base/extlib.h; doc/c-api.md, "Building and linking"), by the
# sonames this header names, written for every build and replaced only
# when they change (a new GDAL), so that only their loaders recompile.
EXTLIB_H  := $(BUILD)/gen/extlib_names.h
CORE_LIBS := $(GSL_LIBS) $(DL_LIBS) -lm
# The shared C library: soname libdfle.so.$(SOMAJOR); the Lua binding and
# the command link the static one, so neither needs it at run time.
SOMAJOR   := 0
SHLIB     := $(BUILD)/libdfle.so.$(VERSION)
LIB_LUA   := $(BUILD)/libdfle_lua.a
CLI       := $(BUILD)/dfle
MODULE    := $(BUILD)/dfle.so

.PHONY: figures all test check fuzz fuzz-long memcheck bench install uninstall clean mpi test-mpi python FORCE
# Keep test objects between builds (make would delete them as intermediates).
.SECONDARY:
all: $(CLI) $(MODULE) $(SHLIB)

# The library is compiled without Lua's headers, so nothing in it can
# depend on Lua; only the binding and the command see them.
$(BUILD)/obj/src/lua/%.o: src/lua/%.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -Isrc $(LUA_CFLAGS) $(GSL_CFLAGS) -MMD -MP -c $< -o $@

$(BUILD)/obj/src/cli/%.o: src/cli/%.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -Isrc $(LUA_CFLAGS) -MMD -MP -c $< -o $@

$(BUILD)/obj/src/%.o: src/%.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -Isrc -I$(BUILD)/gen $(GSL_CFLAGS) $(GDAL_CFLAGS) $(NETCDF_CFLAGS) -MMD -MP -c $< -o $@

$(EXTLIB_H): FORCE
	@mkdir -p $(dir $@)
	@sh scripts/extlib-names.sh '$(CC)' '$(PKG_CONFIG)' > $@.tmp || { rm -f $@.tmp; exit 1; }
	@cmp -s $@.tmp $@ || mv $@.tmp $@; rm -f $@.tmp

$(BUILD)/obj/src/base/gdal_lib.o $(BUILD)/obj/src/base/netcdf_lib.o: $(EXTLIB_H)

$(BUILD)/obj/tests/%.o: tests/%.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -Isrc $(LUA_CFLAGS) $(GSL_CFLAGS) $(GDAL_CFLAGS) $(NETCDF_CFLAGS) $(CMOCKA_CFLAGS) -MMD -MP -c $< -o $@

# Benchmark drivers in C use the library alone.
$(BUILD)/obj/bench/%.o: bench/%.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -MMD -MP -c $< -o $@

# Archives are made anew: one kept from before a source file was removed
# would keep its object, and its symbols.
$(LIB_CORE): $(CORE_OBJ)
	@mkdir -p $(dir $@)
	@rm -f $@
	$(AR) rcs $@ $^

$(LIB_LUA): $(LUA_OBJ)
	@mkdir -p $(dir $@)
	@rm -f $@
	$(AR) rcs $@ $^

$(CLI): $(CLI_OBJ) $(LIB_LUA) $(LIB_CORE)
	$(CC) $(ALL_LDFLAGS) $^ $(LUA_LIBS) $(CORE_LIBS) -o $@

# --no-undefined: a GDAL or netCDF call that bypasses the tables of
# src/base/*_lib.h fails here, not when a program loads the library
# (sanitizer builds leave their runtime's symbols to the executable).
$(SHLIB): $(CORE_OBJ)
	$(CC) -shared -Wl,-soname,libdfle.so.$(SOMAJOR) $(if $(SANITIZE),,-Wl,--no-undefined) \
	    $(ALL_LDFLAGS) $^ $(CORE_LIBS) -o $@

# The Lua module takes its Lua symbols from the host interpreter.
$(MODULE): $(LUA_OBJ) $(CORE_OBJ)
	$(CC) -shared $(ALL_LDFLAGS) $^ $(CORE_LIBS) -o $@

# Tests that read files back with libnetcdf link it themselves.
$(BUILD)/tests/test_netcdf $(BUILD)/tests/test_landscape: TEST_LIBS = $(NETCDF_LIBS)
# Tests that read GeoTIFFs and GeoPackages back with GDAL and OGR link it.
GDAL_LIBS ?= $(shell $(PKG_CONFIG) --libs gdal)
$(BUILD)/tests/test_raster $(BUILD)/tests/test_vector: TEST_LIBS = $(GDAL_LIBS)

$(BUILD)/tests/%: $(BUILD)/obj/tests/%.o $(LIB_LUA) $(LIB_CORE)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_LDFLAGS) $^ $(CMOCKA_LIBS) $(LUA_LIBS) $(TEST_LIBS) $(CORE_LIBS) -o $@

# The CLI's progress bar (its ETA) is not in the library: link it in.
$(BUILD)/tests/test_progress: $(BUILD)/obj/src/cli/progress.o

# The tracer's release gate as a Lua release it was not checked against
# sees it (src/lua/trace/lua_trace_release.c): the gate and its test
# compiled again as if for Lua 5.4.6, the gate linked ahead of the
# library's own, so every law must run as Lua and say why.
GATE_TEST := $(BUILD)/tests/test_trace_release_unchecked
GATE_CFLAGS := -DDFLE_TRACE_ASSUME_RELEASE=50406

$(BUILD)/obj/gate/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) $(GATE_CFLAGS) -Isrc $(LUA_CFLAGS) $(CMOCKA_CFLAGS) -MMD -MP -c $< -o $@

$(GATE_TEST): $(BUILD)/obj/gate/tests/test_trace_release.o \
              $(BUILD)/obj/gate/src/lua/trace/lua_trace_release.o $(LIB_LUA) $(LIB_CORE)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_LDFLAGS) $^ $(CMOCKA_LIBS) $(LUA_LIBS) $(CORE_LIBS) -o $@

# The library when GDAL and libnetcdf cannot be loaded (tests/test_extlib.c):
# their loaders and the test compiled again for sonames no system has,
# the loaders linked ahead of the library's own.
MISSING_TEST := $(BUILD)/tests/test_extlib_missing
MISSING_CFLAGS := -DDFLE_TEST_EXTLIB_MISSING \
    -DDFLE_GDAL_SONAME='"libdfle-test-missing-gdal.so.0"' \
    -DDFLE_NETCDF_SONAME='"libdfle-test-missing-netcdf.so.0"'

$(BUILD)/obj/missing/%.o: %.c $(EXTLIB_H)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) $(MISSING_CFLAGS) -Isrc -I$(BUILD)/gen $(LUA_CFLAGS) $(GDAL_CFLAGS) $(NETCDF_CFLAGS) $(CMOCKA_CFLAGS) -MMD -MP -c $< -o $@

$(MISSING_TEST): $(BUILD)/obj/missing/tests/test_extlib.o $(BUILD)/obj/missing/src/base/gdal_lib.o \
                 $(BUILD)/obj/missing/src/base/netcdf_lib.o $(LIB_LUA) $(LIB_CORE)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_LDFLAGS) $^ $(CMOCKA_LIBS) $(LUA_LIBS) $(CORE_LIBS) -o $@

$(BUILD)/bench/%: $(BUILD)/obj/bench/%.o $(LIB_CORE)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_LDFLAGS) $^ $(CORE_LIBS) -o $@

# The MPI tests join `make test` wherever mpicc is installed (install-deps
# installs it), except in sanitizer builds, where OpenMPI's own
# allocations would drown the report.
HAVE_MPICC := $(if $(SANITIZE),,$(shell command -v $(MPICC) 2>/dev/null))

# The benchmark drivers are built (not run) so they cannot rot.
test: all $(TEST_BIN) $(GATE_TEST) $(MISSING_TEST) $(BENCH_BIN) $(if $(HAVE_PYTHON),python)
	@BUILD=$(BUILD) SANITIZE='$(SANITIZE)' sh tests/run-tests.sh
ifneq ($(HAVE_MPICC),)
	@$(MAKE) --no-print-directory test-mpi
endif

# The sanitizer build, for `make check` and `make fuzz`.
SAN_BUILD := BUILD=build/san OPT=-O1 \
    SANITIZE="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all"

check:
	$(MAKE) $(SAN_BUILD) test

fuzz:
	$(MAKE) $(SAN_BUILD) fuzz-long

fuzz-long: all
	@sh tests/fuzz/run.sh long $(CLI)

memcheck: all $(TEST_BIN) $(GATE_TEST) $(MISSING_TEST)
	@BUILD=$(BUILD) MEMCHECK=1 sh tests/run-tests.sh

bench: all $(BENCH_BIN) $(if $(HAVE_MPICC),$(BUILD)/dfle-mpi) $(if $(HAVE_PYTHON),python)
	@sh bench/run.sh $(CLI) $(BUILD)/bench

# Every example's figures in quick mode, checked against doc/figures.md,
# with an index page and a contact sheet (doc/figures.md).
figures: all
	@DFLE_DATA_DIR="$${DFLE_DATA_DIR:-$(CURDIR)/../shared/data}" $(CLI) doc/gallery.lua $(BUILD)/figures

# --- MPI build (doc/ensembles.md): only these rules need mpicc ---

MPI_CLI   := $(BUILD)/dfle-mpi
MPI_OBJ   := $(BUILD)/obj-mpi/src/cli/main.o $(patsubst %.c,$(BUILD)/obj-mpi/%.o,$(wildcard src/mpi/*.c))

# The MPI driver is compiled without Lua's headers (it serves any
# evaluator); only the command, which plugs the Lua one in, sees them.
$(BUILD)/obj-mpi/src/mpi/%.o: src/mpi/%.c
	@mkdir -p $(dir $@)
	$(MPICC) $(ALL_CFLAGS) -DDFLE_MPI -Isrc -MMD -MP -c $< -o $@

$(BUILD)/obj-mpi/%.o: %.c
	@mkdir -p $(dir $@)
	$(MPICC) $(ALL_CFLAGS) -DDFLE_MPI -Isrc $(LUA_CFLAGS) $(GSL_CFLAGS) -MMD -MP -c $< -o $@

$(MPI_CLI): $(MPI_OBJ) $(BUILD)/obj/src/cli/progress.o $(LIB_LUA) $(LIB_CORE)
	$(MPICC) $(ALL_LDFLAGS) $^ $(LUA_LIBS) $(CORE_LIBS) -o $@

mpi: $(MPI_CLI)

test-mpi: all $(MPI_CLI)
	@BUILD=$(BUILD) sh tests/mpi-ensemble.sh
# --- end MPI build ---

# --- Python (doc/python.md): only these rules need Python ---

# PYTHON and HAVE_PYTHON are set near the top (prerequisites use them).
PY_CFLAGS  = $(shell $(PYTHON) -c 'import sysconfig, numpy; print("-I" + sysconfig.get_paths()["include"], "-I" + numpy.get_include())')
PY_SUFFIX  = $(shell $(PYTHON) -c 'import sysconfig; print(sysconfig.get_config_var("EXT_SUFFIX"))')
PY_VERSION = $(shell $(PYTHON) -c 'import sys; print("%d.%d" % sys.version_info[:2])')
PYTHON_SITE ?= $(PREFIX)/lib/python$(PY_VERSION)/dist-packages
PY_DIR    := $(BUILD)/python
PY_OBJ    := $(patsubst %.c,$(BUILD)/obj/%.o,$(wildcard src/python/*.c))
PY_FILES  := $(patsubst python/%,$(PY_DIR)/%,$(wildcard python/dfle/*.py))
PY_EXT     = $(PY_DIR)/dfle/_dfle$(PY_SUFFIX)

# Python's headers are seen here only (as Lua's in src/lua/).
$(BUILD)/obj/src/python/%.o: src/python/%.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -Isrc $(PY_CFLAGS) -MMD -MP -c $< -o $@

# The extension takes the binding and the library in (static), and
# Python's symbols from the interpreter that loads it.
$(PY_DIR)/dfle/_dfle%: $(PY_OBJ) $(LIB_LUA) $(LIB_CORE)
	@mkdir -p $(dir $@)
	$(CC) -shared $(ALL_LDFLAGS) $^ $(LUA_LIBS) $(CORE_LIBS) -o $@

$(PY_DIR)/dfle/%.py: python/dfle/%.py
	@mkdir -p $(dir $@)
	cp $< $@

python: $(PY_EXT) $(PY_FILES)
# --- end Python ---

INSTALL_MPI := $(if $(HAVE_MPICC),$(MPI_CLI))
DOCDIR := $(DESTDIR)$(PREFIX)/share/doc/dfle
LIBDIR := $(DESTDIR)$(PREFIX)/lib

# Installs the command (and dfle-mpi where mpicc is), the Lua module, the
# C library (static and shared, pkg-config file) and headers, the man
# page, the docs and the examples.  `dfle --help` finds the docs relative
# to its own path, so a DESTDIR or relocated tree works too.
install: all $(INSTALL_MPI) $(if $(HAVE_PYTHON),python)
	install -d $(DESTDIR)$(PREFIX)/bin $(LIBDIR)/lua/5.4 $(LIBDIR)/pkgconfig \
	    $(DESTDIR)$(PREFIX)/include/dfle $(DESTDIR)$(PREFIX)/share/man/man1 $(DOCDIR)/examples
	install -m 755 $(CLI) $(DESTDIR)$(PREFIX)/bin/dfle
	$(if $(INSTALL_MPI),install -m 755 $(MPI_CLI) $(DESTDIR)$(PREFIX)/bin/dfle-mpi)
	install -m 644 $(MODULE) $(LIBDIR)/lua/5.4/dfle.so
	install -m 644 $(LIB_CORE) $(LIBDIR)/libdfle.a
	install -m 644 $(LIB_LUA) $(LIBDIR)/libdfle_lua.a
	install -m 755 $(SHLIB) $(LIBDIR)/libdfle.so.$(VERSION)
	ln -sf libdfle.so.$(VERSION) $(LIBDIR)/libdfle.so.$(SOMAJOR)
	ln -sf libdfle.so.$(SOMAJOR) $(LIBDIR)/libdfle.so
	printf 'prefix=%s\nincludedir=$${prefix}/include\nlibdir=$${prefix}/lib\n\nName: dfle\nDescription: debris-flow and fluvial channel-profile model (C library)\nVersion: %s\nRequires: gsl\nLibs: -L$${libdir} -ldfle $(DL_LIBS) -lm -pthread\nCflags: -I$${includedir}\n' \
	    '$(PREFIX)' '$(VERSION)' > $(LIBDIR)/pkgconfig/dfle.pc
	install -m 644 include/dfle/*.h $(DESTDIR)$(PREFIX)/include/dfle/
	install -m 644 doc/dfle.1 $(DESTDIR)$(PREFIX)/share/man/man1/dfle.1
	install -m 644 README.md doc/*.md $(DOCDIR)/
	install -m 644 examples/*.lua $(DOCDIR)/examples/
	$(if $(HAVE_PYTHON),install -d $(DESTDIR)$(PYTHON_SITE)/dfle && \
	    install -m 644 $(PY_FILES) $(DESTDIR)$(PYTHON_SITE)/dfle/ && \
	    install -m 644 $(PY_EXT) $(DESTDIR)$(PYTHON_SITE)/dfle/)

uninstall:
	rm -f $(DESTDIR)$(PREFIX)/bin/dfle $(DESTDIR)$(PREFIX)/bin/dfle-mpi \
	    $(LIBDIR)/lua/5.4/dfle.so $(LIBDIR)/libdfle.a $(LIBDIR)/libdfle_lua.a \
	    $(LIBDIR)/libdfle.so.$(VERSION) $(LIBDIR)/libdfle.so.$(SOMAJOR) $(LIBDIR)/libdfle.so \
	    $(LIBDIR)/pkgconfig/dfle.pc $(DESTDIR)$(PREFIX)/share/man/man1/dfle.1
	rm -rf $(DESTDIR)$(PREFIX)/include/dfle $(DOCDIR)
	$(if $(HAVE_PYTHON),rm -rf $(DESTDIR)$(PYTHON_SITE)/dfle)

clean:
	rm -rf build

-include $(shell find $(BUILD)/obj $(BUILD)/obj-mpi -name '*.d' 2>/dev/null)
