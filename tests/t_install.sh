#!/bin/sh
# t_install.sh — cellar as an installed library, used as a user uses it (README "The library"):
#   - `make install` twice from the build directory under test: staged (DESTDIR, PREFIX
#     /opt/cellar-test) and plain (PREFIX in a temporary directory); the files, the two
#     symlinks, cellar.pc for its PREFIX, nothing that refers to the build tree (no RPATH or
#     RUNPATH, no path of the build in cellar.pc);
#   - the shared library's SONAME is libcellar.so.0 and it exports exactly the functions
#     CELLAR_EXPORT declares in include/cellar.h; the static library's global names are those
#     too (its internal names are local: a program defining sort_u64 links with it, whereas it
#     does not link with the internal archive $BUILD/libcellar.a);
#   - the installed cellar.h compiles alone as C17 (-pedantic) and as C++;
#   - tests/install_prog.c (the entry points on known answers) and the README's C example,
#     compiled with nothing but `pkg-config --cflags --libs cellar`, shared (run with
#     LD_LIBRARY_PATH) and static (`pkg-config --static`, -Bstatic -lcellar), for each install;
#   - the installed `cellar --version` runs; `make uninstall` removes every file.
# The build directory is the one under test ($CELLAR_BUILD: build, or build/san under make
# check).  It must be up to date: make install would otherwise compile into it with the
# default flags, so a plain build is made here, a sanitized one is a failure (make check's
# `tests` builds the libraries).  When the library was built with sanitizers, the programs
# are compiled with the same -fsanitize (a sanitized libcellar.so needs their runtime first).
# Usage: tests/t_install.sh   (tests/run.sh runs it from the repository's top)
set -u
cd "$(dirname "$0")/.." || exit 1
. tests/lib.sh
B=${CELLAR_BUILD:-build}
case $B in /*) ;; *) B="$(pwd)/$B" ;; esac
TOP=$(pwd)
CC=${CC:-cc}
for c in pkg-config nm readelf "$CC" g++ make; do
    command -v "$c" >/dev/null 2>&1 || give_up "install: $c is missing (make deps installs it)"
done
# a make of our own: none of the caller's make flags or variables (SAN, OPT, ...)
mk() { env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL make --no-print-directory BUILD="$B" "$@"; }

SAN=""
if [ "${CELLAR_SANITIZED:-0}" = 1 ] ||
    { [ -x "$B/cellar" ] && readelf -d "$B/cellar" | grep -q 'libasan'; }; then
    SAN="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
fi
if ! mk -q all >/dev/null 2>&1; then
    [ -n "$SAN" ] && give_up "install: $B is not up to date (make check builds it)"
    echo "install: building $B"
    mk all >"$T/build.log" 2>&1 || {
        tail -n 20 "$T/build.log"
        give_up "install: make BUILD=$B all failed"
    }
fi

# the version and the exported functions, from the header
H=include/cellar.h
VER=$(sed -n 's/^#define CELLAR_VERSION_\(MAJOR\|MINOR\|PATCH\) \([0-9]*\)$/\2/p' $H | paste -sd.)
grep '^CELLAR_EXPORT ' $H | sed 's/^[^(]*[ *]\(cellar_[a-z0-9_]*\)(.*/\1/' | sort >"$T/api"
NAPI=$(grep -c '^CELLAR_EXPORT ' $H)
echo "  header: version $VER, $NAPI exported functions"
check "the header declares a version and its CELLAR_EXPORT functions are cellar_* names" \
    sh -c "echo '$VER' | grep -qE '^[0-9]+\.[0-9]+\.[0-9]+$' && [ $NAPI -gt 0 ] &&
        [ \$(grep -c '^cellar_[a-z0-9_]*$' '$T/api') -eq $NAPI ]"
MAJOR=${VER%%.*}

# the files of one installed tree ROOT made for PREFIX
check_tree() {
    root=$1 prefix=$2 what=$3
    ok=1
    for f in bin/cellar bin/cellard include/cellar.h "lib/libcellar.so.$VER" lib/libcellar.a \
        lib/pkgconfig/cellar.pc; do
        [ -f "$root/$f" ] && [ ! -L "$root/$f" ] || {
            echo "  missing: $root/$f"
            ok=0
        }
    done
    [ -x "$root/bin/cellar" ] && [ -x "$root/bin/cellard" ] || ok=0
    check "$what: bin/cellar, bin/cellard, include/cellar.h, lib/libcellar.so.$VER, lib/libcellar.a, cellar.pc" \
        [ $ok = 1 ]
    check "$what: lib/libcellar.so.$MAJOR -> libcellar.so.$VER, lib/libcellar.so -> libcellar.so.$MAJOR" \
        sh -c "[ \"\$(readlink '$root/lib/libcellar.so.$MAJOR')\" = libcellar.so.$VER ] &&
            [ \"\$(readlink '$root/lib/libcellar.so')\" = libcellar.so.$MAJOR ]"
    check "$what: the installed header is include/cellar.h" cmp -s $H "$root/include/cellar.h"
    check "$what: cellar.pc says prefix=$prefix and Version: $VER" \
        sh -c "grep -qx 'prefix=$prefix' '$root/lib/pkgconfig/cellar.pc' &&
            grep -qx 'Version: $VER' '$root/lib/pkgconfig/cellar.pc'"
    check "$what: cellar.pc names no path of the build tree" \
        sh -c "! grep -qF '$TOP' '$root/lib/pkgconfig/cellar.pc'"
    check "$what: no RPATH or RUNPATH in the library and the programs" \
        sh -c "! readelf -d '$root/lib/libcellar.so.$VER' '$root/bin/cellar' '$root/bin/cellard' |
            grep -qE 'RPATH|RUNPATH'"
    check "$what: the SONAME is libcellar.so.$MAJOR" \
        sh -c "readelf -d '$root/lib/libcellar.so.$VER' | grep SONAME |
            grep -qF '[libcellar.so.$MAJOR]'"
    nm -D --defined-only "$root/lib/libcellar.so.$VER" | awk 'NF == 3 {print $3}' | sort >"$T/dyn"
    echo "  $(wc -l <"$T/dyn") dynamic symbols; not in the header: $(comm -13 "$T/api" "$T/dyn" | head -5 | tr '\n' ' ')"
    check "$what: the shared library exports exactly the header's $NAPI functions" cmp -s "$T/api" "$T/dyn"
    nm -g --defined-only "$root/lib/libcellar.a" | awk 'NF == 3 {print $3}' | sort >"$T/sta"
    echo "  $(wc -l <"$T/sta") global symbols in libcellar.a; not in the header: $(comm -13 "$T/api" "$T/sta" | head -5 | tr '\n' ' ')"
    check "$what: the static library's global names are exactly the header's $NAPI functions" \
        cmp -s "$T/api" "$T/sta"
    check "$what: the installed cellar --version runs" \
        sh -c "'$root/bin/cellar' --version >'$T/ver' 2>&1 && grep -q '^cellar ' '$T/ver'"
}

# run_prog WHAT LIBDIR PROG: runs install_prog with LD_LIBRARY_PATH=LIBDIR (none when empty),
# its checks named after WHAT; then one more check: it ran to its summary line and exited 0,
# or 1 with its failures said (not a crash, not a sanitizer's report)
run_prog() {
    if [ -n "$2" ]; then
        env LD_LIBRARY_PATH="$2" "$3" >"$T/prog.out" 2>&1
    else
        env -u LD_LIBRARY_PATH "$3" >"$T/prog.out" 2>&1
    fi
    rc=$?
    sed -e "s/^ok /ok $1: /" -e "s/^FAIL /FAIL $1: /" "$T/prog.out" >"$T/prog.tally"
    tally_file "$T/prog.tally"
    if grep -qE '^[0-9]+ passed, [0-9]+ failed' "$T/prog.out" &&
        { [ $rc -eq 0 ] || { [ $rc -eq 1 ] && grep -q '^FAIL ' "$T/prog.out"; }; }; then
        pass "$1: install_prog ran to its end"
    else
        echo "  exit $rc"
        fail "$1: install_prog ran to its end"
    fi
}

# compiles and runs tests/install_prog.c and the README's example against one installed tree,
# with the environment that makes pkg-config find it (PKG_CONFIG_PATH, and for a staged
# install PKG_CONFIG_SYSROOT_DIR)
use_tree() {
    root=$1 what=$2
    pc() { pkg-config "$@" cellar; }
    check "$what: pkg-config --modversion cellar is $VER" [ "$(pc --modversion)" = "$VER" ]
    got=$(echo $(pc --cflags))
    [ "$got" = "-I$root/include" ] || echo "  pkg-config --cflags: $got"
    check "$what: pkg-config --cflags is -I<the installed tree>/include" [ "$got" = "-I$root/include" ]
    hdr="$T/hdr.c"
    echo '#include <cellar.h>' >"$hdr"
    check "$what: cellar.h compiles alone (C17 -pedantic)" \
        status 0 "$CC" -std=c17 -Wall -Wextra -Werror -pedantic $(pc --cflags) -c "$hdr" -o "$T/hdr.o"
    check "$what: cellar.h compiles alone as C++ (g++ -x c++ -pedantic)" \
        status 0 g++ -x c++ -std=c++17 -Wall -Wextra -Werror -pedantic $(pc --cflags) -c "$hdr" -o "$T/hdr.o"
    cf="-std=c17 -O1 -g -Wall -Wextra -Werror $SAN"
    # shared
    rm -f "$T/prog"
    if status 0 "$CC" $cf tests/install_prog.c -o "$T/prog" $(pc --cflags --libs); then
        pass "$what: install_prog.c builds with pkg-config --cflags --libs cellar"
        check "$what: it needs libcellar.so.$MAJOR, found in the installed tree" \
            sh -c "readelf -d '$T/prog' | grep NEEDED | grep -qF '[libcellar.so.$MAJOR]' &&
                LD_LIBRARY_PATH='$root/lib' ldd '$T/prog' |
                grep -qF 'libcellar.so.$MAJOR => $root/lib/libcellar.so.$MAJOR'"
        run_prog "$what, shared" "$root/lib" "$T/prog"
    else
        cat "$T/err"
        fail "$what: install_prog.c builds with pkg-config --cflags --libs cellar"
    fi
    # static: libcellar.a, its dependencies from Libs.private
    rm -f "$T/prog_s"
    sl=$(pc --static --libs | sed 's/-lcellar\( \|$\)/-Wl,-Bstatic -lcellar -Wl,-Bdynamic /')
    if status 0 "$CC" $cf $(pc --static --cflags) tests/install_prog.c -o "$T/prog_s" $sl; then
        pass "$what: install_prog.c links statically with pkg-config --static"
        check "$what: the static program needs no libcellar.so" \
            sh -c "! readelf -d '$T/prog_s' | grep NEEDED | grep -q libcellar"
        run_prog "$what, static" "" "$T/prog_s"
    else
        cat "$T/err"
        fail "$what: install_prog.c links statically with pkg-config --static"
    fi
    # the README's example, shared and static
    for how in shared static; do
        if [ $how = shared ]; then
            l=$(pc --libs) f=$(pc --cflags)
        else
            l=$sl f=$(pc --static --cflags)
        fi
        rm -f "$T/ex"
        if status 0 "$CC" $cf $f "$T/readme.c" -o "$T/ex" $l &&
            LD_LIBRARY_PATH="$root/lib" "$T/ex" >"$T/ex.out" 2>"$T/ex.err" &&
            [ "$(cat "$T/ex.out")" = "5 vertices, 8 edges, 4 faces" ]; then
            pass "$what: the README's example ($how) prints 5 vertices, 8 edges, 4 faces"
        else
            head -c 300 "$T/err" "$T/ex.out" "$T/ex.err" 2>/dev/null
            fail "$what: the README's example ($how) prints 5 vertices, 8 edges, 4 faces"
        fi
    done
}

# the README's C example: the ```c block of "## The library"
awk '/^## The library/ {s = 1} s && /^```c$/ {c = 1; next} c && /^```/ {exit} c' README.md \
    >"$T/readme.c"
check "README \"The library\" has a C example" grep -q cellar_arrangement2d "$T/readme.c"

# the internal archive clashes with install_prog.c's own sort_u64, svg_read, ...: the static
# checks below mean something
check "install_prog.c's own internal names clash with the internal archive $B/libcellar.a" \
    sh -c "! $CC -std=c17 $SAN -Iinclude tests/install_prog.c -o '$T/clash' '$B/libcellar.a' \
        -ljansson -lxml2 -lzip -lz -lm -pthread 2>'$T/clash.err' &&
        grep -q 'multiple definition of .sort_u64' '$T/clash.err'"

# 1. staged: DESTDIR, PREFIX=/opt/cellar-test
S="$T/stage"
if status 0 mk install DESTDIR="$S" PREFIX=/opt/cellar-test; then
    pass "make install DESTDIR=... PREFIX=/opt/cellar-test"
    check "DESTDIR: nothing installed outside DESTDIR/opt/cellar-test" \
        sh -c "[ -z \"\$(ls -A '$S' | grep -vx opt)\" ] && [ -z \"\$(ls -A '$S/opt' | grep -vx cellar-test)\" ]"
    check_tree "$S/opt/cellar-test" /opt/cellar-test "DESTDIR"
    export PKG_CONFIG_PATH="$S/opt/cellar-test/lib/pkgconfig" PKG_CONFIG_SYSROOT_DIR="$S"
    use_tree "$S/opt/cellar-test" "DESTDIR"
    unset PKG_CONFIG_PATH PKG_CONFIG_SYSROOT_DIR
else
    cat "$T/out" "$T/err" | tail -n 20
    fail "make install DESTDIR=... PREFIX=/opt/cellar-test"
fi

# 2. plain: PREFIX only
R="$T/prefix"
if status 0 mk install PREFIX="$R"; then
    pass "make install PREFIX=..."
    check_tree "$R" "$R" "PREFIX"
    export PKG_CONFIG_PATH="$R/lib/pkgconfig"
    use_tree "$R" "PREFIX"
    unset PKG_CONFIG_PATH
    if status 0 mk uninstall PREFIX="$R"; then
        check "make uninstall removes every file" \
            sh -c "[ -z \"\$(find '$R' ! -type d)\" ]"
    else
        fail "make uninstall PREFIX=..."
    fi
else
    cat "$T/out" "$T/err" | tail -n 20
    fail "make install PREFIX=..."
fi
finish
