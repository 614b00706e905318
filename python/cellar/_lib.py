"""_lib.py — finds libcellar.so.0 and declares include/cellar.h for ctypes.

Where the library is looked for, in order (the first that loads wins):
  1. the path in the environment variable CELLAR_LIBRARY;
  2. a copy bundled in this package (cellar/libcellar.so.0, put there by the wheel's build);
  3. "libcellar.so.0" through the dynamic loader (`make install` to a prefix on its path);
  4. ctypes.util.find_library("cellar").
None loading is an ImportError that names every place tried and why each failed.

The structs below are those of include/cellar.h, field for field; nothing here calls the
library but cellar_version (the calls are in __init__.py).
"""
import ctypes
import ctypes.util
import os

C = ctypes


class Error_(C.Structure):
    _fields_ = [("status", C.c_int), ("msg", C.c_char * 256)]


PROGRESS = C.CFUNCTYPE(None, C.c_void_p, C.c_char_p, C.c_double)
CANCEL = C.CFUNCTYPE(C.c_int, C.c_void_p)


class Options(C.Structure):
    _fields_ = [
        ("precision", C.c_double),
        ("threads", C.c_int),
        ("fields", C.c_char_p),
        ("fill", C.c_char_p),
        ("keep_dangling", C.c_int),
        ("operators", C.c_int),
        ("cancel", CANCEL),
        ("progress", PROGRESS),
        ("udata", C.c_void_p),
    ]


class Array(C.Structure):
    _fields_ = [
        ("name", C.c_char_p),
        ("dtype", C.c_int),
        ("rows", C.c_size_t),
        ("cols", C.c_size_t),
        ("data", C.c_void_p),
    ]


class Solid(C.Structure):
    _fields_ = [
        ("V", C.c_void_p),
        ("nv", C.c_size_t),
        ("F", C.c_void_p),
        ("face_off", C.c_void_p),
        ("nf", C.c_size_t),
    ]


def _candidates():
    env = os.environ.get("CELLAR_LIBRARY")
    if env:
        yield "CELLAR_LIBRARY=" + env, env
    here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "libcellar.so.0")
    if os.path.exists(here):
        yield "the bundled " + here, here
    yield "libcellar.so.0 (the dynamic loader's path)", "libcellar.so.0"
    found = C.util.find_library("cellar")
    if found:
        yield "ctypes.util.find_library('cellar') = " + found, found


def _load():
    tried = []
    for what, path in _candidates():
        try:
            return C.CDLL(path), path
        except OSError as e:
            tried.append("%s: %s" % (what, e))
    tried.append("ctypes.util.find_library('cellar'): nothing found")
    raise ImportError("cellar: libcellar.so.0 could not be loaded; tried\n  " + "\n  ".join(tried) +
                      "\nBuild it (make build/lib/libcellar.so.0.3.0) and set CELLAR_LIBRARY to "
                      "its path, or `make install` it, or pip install the package from a tree "
                      "where it is built (the wheel then bundles it).")


lib, path = _load()

P = C.c_void_p
RESULT_PP = C.POINTER(C.c_void_p)
ERR_P = C.POINTER(Error_)
OPT_P = C.POINTER(Options)

lib.cellar_arrangement2d.argtypes = [P, C.c_size_t, OPT_P, RESULT_PP, ERR_P]
lib.cellar_polygons.argtypes = [C.c_size_t, P, P, P, C.c_char_p, OPT_P, RESULT_PP, ERR_P]
lib.cellar_solids.argtypes = [C.POINTER(Solid), C.c_size_t, C.c_char_p, OPT_P, RESULT_PP, ERR_P]
lib.cellar_run_json.argtypes = [C.c_char_p, C.c_size_t, OPT_P, C.POINTER(C.c_void_p),
                                C.POINTER(C.c_size_t), ERR_P]
for f in ("cellar_arrangement2d", "cellar_polygons", "cellar_solids", "cellar_run_json"):
    getattr(lib, f).restype = C.c_int
lib.cellar_result_count.argtypes = [P]
lib.cellar_result_count.restype = C.c_size_t
lib.cellar_result_array.argtypes = [P, C.c_size_t]
lib.cellar_result_array.restype = C.POINTER(Array)
lib.cellar_result_dim.argtypes = [P]
lib.cellar_result_dim.restype = C.c_int
lib.cellar_result_json.argtypes = [P]
lib.cellar_result_json.restype = C.c_char_p
lib.cellar_result_free.argtypes = [P]
lib.cellar_result_free.restype = None
lib.cellar_free.argtypes = [P]
lib.cellar_free.restype = None
lib.cellar_stage_name.argtypes = [C.c_char_p, C.c_size_t]
lib.cellar_stage_name.restype = C.c_char_p
lib.cellar_version.argtypes = []
lib.cellar_version.restype = C.c_char_p
