# cellar — build, test, bench.  See README.md.
#   make          build build/cellar
#   make deps     install the Debian packages needed to build and test
#   make test     deps + build + whole suite; last line: "N passed, N failed"
#   make check    the suite again under AddressSanitizer + UndefinedBehaviorSanitizer
#   make stress   the random 3D families (STRESS seeds, 1000) and 2D Boolean ones (not in CI)
#   make bench    reference programs (CGAL, GEOS) and the comparison tables, 2D and 3D
#   make run      build and start the service (see README)

BUILD   ?= build
CC      ?= cc
CXX     ?= g++
OPT     ?= -O2
SAN     ?=
CFLAGS  += -std=c17 $(OPT) -g -Wall -Wextra -Werror -pthread -D_GNU_SOURCE $(SAN)
CPPFLAGS += -I. -I/usr/include/libxml2 -I/usr/include/postgresql
LDLIBS  += -lm -pthread
JANSSON_LIBS := -ljansson -lxml2 -lzip
GEOS_LIBS    := -lgeos_c
SERVER_LIBS  := -lmicrohttpd -lsqlite3 -lpq -lcrypto -lz
TEST_LIBS    := $(SERVER_LIBS) -lcurl $(JANSSON_LIBS) $(GEOS_LIBS)

DEPS_RUN   := gcc make libc6-dev libjansson-dev libmicrohttpd-dev libsqlite3-dev libssl-dev \
              libxml2-dev libpq-dev zlib1g-dev libzip-dev nodejs npm
DEPS_BUILD := $(DEPS_RUN) libgeos-dev libcurl4-openssl-dev curl python3 python3-jsonschema \
              python3-shapely python3-numpy python3-scipy python3-venv python3-pip sqlite3 \
              g++ libcgal-dev libgmp-dev libmpfr-dev libboost-dev clang libclang-rt-14-dev \
              postgresql postgresql-client nginx-light \
              podman podman-compose runc conmon slirp4netns netavark aardvark-dns iptables \
              catatonit debootstrap bc gdal-bin time pkgconf binutils
DEPS_BENCH := g++ libcgal-dev libgmp-dev libmpfr-dev libboost-dev time

LIB_VERSION := $(shell sed -n 's/^\#define API_VERSION "\(.*\)"/\1/p' api/api.h)
LIB_SONAME  := libcellar.so.0
CORE_SRC := $(wildcard core/*.c)
API_SRC  := $(wildcard api/*.c)
CORE_OBJ := $(CORE_SRC:%.c=$(BUILD)/%.o)
API_OBJ  := $(API_SRC:%.c=$(BUILD)/%.o)
SERVER_SRC := $(filter-out server/main.c,$(wildcard server/*.c))
SERVER_OBJ := $(SERVER_SRC:%.c=$(BUILD)/%.o) $(BUILD)/gen/openapi.o $(BUILD)/gen/web.o
WEB_SRC  := web/index.html web/style.css web/build.mjs web/package.json web/package-lock.json \
            $(wildcard web/src/*.js) $(wildcard examples/*)
TEST_SRC := $(wildcard tests/test_*.c)
TEST_BIN := $(TEST_SRC:tests/%.c=$(BUILD)/tests/%)
TEST_LIB := $(BUILD)/tests/testlib.o $(BUILD)/tests/lar_check.o $(BUILD)/tests/shapes.o \
            $(BUILD)/tests/ref/geos_ref.o $(BUILD)/tests/daemon.o $(BUILD)/tests/pg.o

.PHONY: all deps test check stress bench run clean format format-check tests fuzz install \
        uninstall
# the tests' shared objects are not intermediates (two makes at once must find them)
.SECONDARY: $(TEST_LIB)
all: $(BUILD)/cellar $(BUILD)/cellard $(BUILD)/lib/libcellar.so.$(LIB_VERSION) \
     $(BUILD)/lib/libcellar.a


deps:
	@scripts/deps.sh $(DEPS_BUILD)
	@scripts/browser-deps.sh
	@scripts/npm-deps.sh tests/lint

$(BUILD)/%.o: %.c $(wildcard core/*.h api/*.h server/*.h tests/*.h)
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -c $< -o $@

# The library's objects are position-independent, and only the names of include/cellar.h
# (CELLAR_EXPORT) are visible outside it: libcellar.so exports cellar_* alone.
$(CORE_OBJ) $(API_OBJ): CFLAGS += -fPIC -fvisibility=hidden

$(BUILD)/libcellar.a: $(CORE_OBJ) $(API_OBJ)
	@rm -f $@
	ar rcs $@ $^

$(BUILD)/lib/libcellar.so.$(LIB_VERSION): $(CORE_OBJ) $(API_OBJ)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) -shared -Wl,-soname,$(LIB_SONAME) -Wl,--no-undefined -o $@ $^ \
	    $(JANSSON_LIBS) -lz $(LDLIBS)
	ln -sf libcellar.so.$(LIB_VERSION) $(BUILD)/lib/$(LIB_SONAME)
	ln -sf $(LIB_SONAME) $(BUILD)/lib/libcellar.so

# The users' static library: the same objects as one relocatable object whose hidden symbols
# are made local, so that only the names of include/cellar.h are global in it and a program
# linking it cannot clash with our internal names (sort_u64, svg_read, ...).  $(BUILD)/libcellar.a
# above, the internal archive, keeps them all: the CLI, the daemon and the tests use them.
$(BUILD)/lib/libcellar.a: $(CORE_OBJ) $(API_OBJ)
	@mkdir -p $(dir $@)
	$(LD) -r -o $(BUILD)/lib/cellar.o $^
	$(OBJCOPY) --localize-hidden $(BUILD)/lib/cellar.o
	@rm -f $@
	$(AR) rcs $@ $(BUILD)/lib/cellar.o

# make install [PREFIX=/usr/local] [DESTDIR=]: the CLI and the daemon, the header, the shared
# library (and its two names), the static one and cellar.pc (from cellar.pc.in, for PREFIX;
# DESTDIR only stages the files).  Nothing installed refers to the build tree.
PREFIX  ?= /usr/local
DESTDIR ?=
BINDIR  := $(DESTDIR)$(PREFIX)/bin
INCDIR  := $(DESTDIR)$(PREFIX)/include
LIBDIR  := $(DESTDIR)$(PREFIX)/lib
LD      ?= ld
OBJCOPY ?= objcopy
INSTALL ?= install

install: all
	$(INSTALL) -d $(BINDIR) $(INCDIR) $(LIBDIR)/pkgconfig
	$(INSTALL) -m 755 $(BUILD)/cellar $(BUILD)/cellard $(BINDIR)/
	$(INSTALL) -m 644 include/cellar.h $(INCDIR)/
	$(INSTALL) -m 755 $(BUILD)/lib/libcellar.so.$(LIB_VERSION) $(LIBDIR)/
	ln -sf libcellar.so.$(LIB_VERSION) $(LIBDIR)/$(LIB_SONAME)
	ln -sf $(LIB_SONAME) $(LIBDIR)/libcellar.so
	$(INSTALL) -m 644 $(BUILD)/lib/libcellar.a $(LIBDIR)/
	sed -e 's|@PREFIX@|$(PREFIX)|g' -e 's|@VERSION@|$(LIB_VERSION)|g' cellar.pc.in \
	    > $(LIBDIR)/pkgconfig/cellar.pc
	chmod 644 $(LIBDIR)/pkgconfig/cellar.pc

uninstall:
	rm -f $(BINDIR)/cellar $(BINDIR)/cellard $(INCDIR)/cellar.h \
	    $(LIBDIR)/libcellar.so.$(LIB_VERSION) $(LIBDIR)/$(LIB_SONAME) $(LIBDIR)/libcellar.so \
	    $(LIBDIR)/libcellar.a $(LIBDIR)/pkgconfig/cellar.pc

$(BUILD)/cellar: $(BUILD)/cli/cellar.o $(BUILD)/libcellar.a
	$(CC) $(CFLAGS) -o $@ $^ $(JANSSON_LIBS) -lz $(LDLIBS)

$(BUILD)/gen/openapi.c: schemas/openapi.json scripts/embed.sh
	@mkdir -p $(dir $@)
	scripts/embed.sh cellar_openapi schemas/openapi.json > $@

$(BUILD)/gen/openapi.o: $(BUILD)/gen/openapi.c
	$(CC) $(CFLAGS) -c $< -o $@

# The page at / (web/): bundled by esbuild (npm ci in web/ first when web/node_modules is
# missing or stale: node and npm are build dependencies), then embedded as a table of assets.
$(BUILD)/web/assets.list: $(WEB_SRC) scripts/web-build.sh
	scripts/web-build.sh $(BUILD)/web

$(BUILD)/gen/web.c: $(BUILD)/web/assets.list scripts/web-embed.sh
	@mkdir -p $(dir $@)
	scripts/web-embed.sh $(BUILD)/web > $@.tmp && mv $@.tmp $@

$(BUILD)/gen/web.o: $(BUILD)/gen/web.c server/webassets.h
	$(CC) $(CPPFLAGS) $(CFLAGS) -c $< -o $@

$(BUILD)/libcellard.a: $(SERVER_OBJ)
	@rm -f $@
	ar rcs $@ $^

$(BUILD)/cellard: $(BUILD)/server/main.o $(BUILD)/libcellard.a $(BUILD)/libcellar.a
	$(CC) $(CFLAGS) -o $@ $^ $(SERVER_LIBS) $(JANSSON_LIBS) $(LDLIBS)

$(BUILD)/tests/%: $(BUILD)/tests/%.o $(TEST_LIB) $(BUILD)/libcellard.a $(BUILD)/libcellar.a
	$(CC) $(CFLAGS) -o $@ $^ $(TEST_LIBS) $(LDLIBS)

tests: $(BUILD)/cellar $(BUILD)/cellard $(BUILD)/lib/libcellar.so.$(LIB_VERSION) \
       $(BUILD)/lib/libcellar.a $(TEST_BIN) $(BUILD)/tests/ref/cgal_bool $(BUILD)/tests/ref/cgal_nef

# The CGAL reference of the 3D tests (C++, header-only CGAL: about 1.5 min to compile).  Built
# without sanitizers; make check copies it from $(BUILD) instead of compiling it again.
$(BUILD)/tests/ref/cgal_bool: tests/ref/cgal_bool.cpp tests/ref/cgal_soup.hpp
	@mkdir -p $(dir $@)
	$(CXX) -std=c++17 -O2 -DNDEBUG -o $@ $< -lgmp -lmpfr

$(BUILD)/tests/ref/cgal_nef: tests/ref/cgal_nef.cpp tests/ref/cgal_soup.hpp
	@mkdir -p $(dir $@)
	$(CXX) -std=c++17 -O2 -DNDEBUG -o $@ $< -lgmp -lmpfr

test: deps
	@$(MAKE) --no-print-directory tests
	@tests/run.sh $(BUILD)

check: deps
	@$(MAKE) --no-print-directory $(BUILD)/tests/ref/cgal_bool $(BUILD)/tests/ref/cgal_nef
	@mkdir -p build/san/tests/ref && cp -p $(BUILD)/tests/ref/cgal_bool $(BUILD)/tests/ref/cgal_nef \
	    build/san/tests/ref/
	@$(MAKE) --no-print-directory BUILD=build/san OPT=-O1 \
	    SAN="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer" tests
	@ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
	    CELLAR_SANITIZED=1 tests/run.sh build/san

# The random 3D families at STRESS seeds each (contacts, slivers, near-coplanar faces, lattice
# scenes, real meshes), every invariant and every volume checked, the 2D torture families
# (STRESS x 3600 degenerate scenes, lar_check on each), and the 2D Boolean families
# against GEOS at BOOL2_STRESS batches of 200 cases each (20: 60 000 cases, 600 000 runs):
# tens of minutes, not in CI.
STRESS ?= 1000
BOOL2_STRESS ?= 20
stress: deps
	@$(MAKE) --no-print-directory tests
	@CELLAR_STRESS=$(STRESS) tests/run.sh $(BUILD) test_exact3d t_real3d t_contacts3d test_torture \
	    test_winding3d t_winding3d t_winding2d test_packed test_core
	@CELLAR_STRESS=$(BOOL2_STRESS) tests/run.sh $(BUILD) test_bool2_geos

bench: deps
	@scripts/deps.sh $(DEPS_BENCH)
	@$(MAKE) --no-print-directory $(BUILD)/cellar $(BUILD)/lib/libcellar.so.$(LIB_VERSION) \
	    $(BUILD)/bench/cgal_arrangement \
	    $(BUILD)/bench/geos_polygonize $(BUILD)/bench/geos_bool2 $(BUILD)/tests/ref/cgal_bool \
	    $(BUILD)/bench/io
	@if command -v npm >/dev/null 2>&1 && [ ! -d bench/node_modules/manifold-3d ]; then \
	    npm ci --prefix bench --no-audit --no-fund >/dev/null 2>&1 || \
	    echo "bench: npm ci --prefix bench failed: manifold is skipped" >&2; fi
	@s=0; bench/run.sh $(BUILD) || s=1; echo; bench/io.sh $(BUILD) || s=1; echo; \
	    bench/run3d.sh $(BUILD) || s=1; echo; \
	    bench/runbool.sh $(BUILD) || s=1; echo; bench/runbool2.sh $(BUILD) || s=1; echo; \
	    bench/runmany.sh $(BUILD) || s=1; echo; \
	    python3 bench/mesh3.py $(BUILD) $(BENCH_MESH3_ARGS) || s=1; echo; \
	    python3 bench/lib_bench.py $(BUILD) || s=1; exit $$s

$(BUILD)/bench/cgal_arrangement: bench/cgal_arrangement.cpp
	@mkdir -p $(dir $@)
	$(CXX) -std=c++17 -O2 -DNDEBUG -o $@ $< -ljansson -lgmp -lmpfr

$(BUILD)/bench/geos_bool2: bench/geos_bool2.c tests/ref/geos_ref.c tests/ref/geos_ref.h
	@mkdir -p $(dir $@)
	$(CC) -std=c17 -O2 -Wall -Wextra -Werror -I. -o $@ bench/geos_bool2.c tests/ref/geos_ref.c -ljansson -lgeos_c -lm

$(BUILD)/bench/io: $(BUILD)/bench/io.o $(BUILD)/libcellar.a
	$(CC) $(CFLAGS) -o $@ $^ $(JANSSON_LIBS) -lz $(LDLIBS)

$(BUILD)/bench/geos_polygonize: bench/geos_polygonize.c tests/ref/geos_ref.c tests/ref/geos_ref.h
	@mkdir -p $(dir $@)
	$(CC) -std=c17 -O2 -Wall -Wextra -Werror -I. -o $@ bench/geos_polygonize.c tests/ref/geos_ref.c -ljansson -lgeos_c -lm

run:
	@scripts/deps.sh $(DEPS_RUN)
	@$(MAKE) --no-print-directory all
	@scripts/run.sh $(BUILD) $(ARGS)

format:
	clang-format -i include/*.h core/*.[ch] api/*.[ch] server/*.[ch] cli/*.c tests/*.[ch] tests/ref/*.[ch] \
	    tests/ref/*.cpp tests/ref/*.hpp tests/fuzz/*.[ch]

format-check:
	clang-format --dry-run -Werror include/*.h core/*.[ch] api/*.[ch] server/*.[ch] cli/*.c tests/*.[ch] \
	    tests/ref/*.[ch] tests/ref/*.cpp tests/ref/*.hpp tests/fuzz/*.[ch]

clean:
	rm -rf build

include tests/fuzz/fuzz.mk
