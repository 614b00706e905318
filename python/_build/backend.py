"""backend.py — cellar's in-tree PEP 517 build backend (standard library only).

pip (pyproject.toml: requires = [], backend-path = ["_build"]) imports it to build a wheel
with nothing downloaded.  The wheel holds cellar/*.py and cellar-VERSION.dist-info (METADATA
from pyproject.toml's [project], WHEEL, RECORD with each file's sha256).  The library is
bundled as cellar/libcellar.so.0 when found: the file CELLAR_LIBRARY names, else
../build/lib/libcellar.so.0 (symlinks resolved); the wheel is then tagged
py3-none-<platform> (sysconfig), else it is py3-none-any and uses the installed library.
build_editable puts a .pth naming this directory instead of the package's files.
"""
import base64, hashlib, io, os, re, sysconfig, tarfile, zipfile

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # python/


def _project():
    text = open(os.path.join(HERE, "pyproject.toml"), encoding="utf-8").read()
    try:
        import tomllib
        return tomllib.loads(text)["project"]
    except ImportError:  # Python < 3.11: the few keys used, by pattern
        g = lambda k: re.search(r'^%s\s*=\s*"([^"]*)"' % k, text, re.M).group(1)
        deps = re.search(r"^dependencies\s*=\s*\[(.*?)\]", text, re.M | re.S).group(1)
        return {"name": g("name"), "version": g("version"), "description": g("description"),
                "requires-python": g("requires-python"),
                "dependencies": re.findall(r'"([^"]+)"', deps)}


def _metadata():
    p = _project()
    lines = ["Metadata-Version: 2.1", "Name: " + p["name"], "Version: " + p["version"],
             "Summary: " + p.get("description", ""), "License: MIT"]
    if "requires-python" in p:
        lines.append("Requires-Python: " + p["requires-python"])
    lines += ["Requires-Dist: " + d for d in p.get("dependencies", [])]
    for extra, deps in p.get("optional-dependencies", {}).items():
        lines.append("Provides-Extra: " + extra)
        lines += ['Requires-Dist: %s; extra == "%s"' % (d, extra) for d in deps]
    readme = os.path.join(HERE, "README.md")
    if os.path.exists(readme):
        lines.append("Description-Content-Type: text/markdown")
        lines += ["", open(readme, encoding="utf-8").read()]
    return p["name"], p["version"], ("\n".join(lines) + "\n").encode()


def _library():
    path = os.environ.get("CELLAR_LIBRARY") or os.path.join(HERE, "..", "build", "lib",
                                                            "libcellar.so.0")
    path = os.path.realpath(path)
    return path if os.path.isfile(path) else None


def _tag(lib):
    if not lib:
        return "py3-none-any"
    return "py3-none-" + re.sub(r"[^A-Za-z0-9]", "_", sysconfig.get_platform())


def _wheel(wheel_directory, files, lib):
    name, version, meta = _metadata()
    tag = _tag(lib)
    dist = "%s-%s.dist-info" % (name, version)
    files = list(files) + [
        (dist + "/METADATA", meta),
        (dist + "/WHEEL", ("Wheel-Version: 1.0\nGenerator: cellar _build/backend.py\n"
                           "Root-Is-Purelib: %s\nTag: %s\n" % ("false" if lib else "true",
                                                                tag)).encode()),
    ]
    record = []
    fn = "%s-%s-%s.whl" % (name, version, tag)
    with zipfile.ZipFile(os.path.join(wheel_directory, fn), "w", zipfile.ZIP_DEFLATED) as z:
        for arc, data in files:
            info = zipfile.ZipInfo(arc, (1980, 1, 1, 0, 0, 0))
            info.external_attr = (0o755 if arc.endswith(".so.0") else 0o644) << 16
            info.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(info, data)
            h = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
            record.append("%s,sha256=%s,%d" % (arc, h, len(data)))
        record.append(dist + "/RECORD,,")
        z.writestr(zipfile.ZipInfo(dist + "/RECORD", (1980, 1, 1, 0, 0, 0)),
                   "\n".join(record) + "\n")
    return fn


def _sources():
    pkg = os.path.join(HERE, "cellar")
    for f in sorted(os.listdir(pkg)):
        if f.endswith(".py"):
            yield "cellar/" + f, open(os.path.join(pkg, f), "rb").read()


def get_requires_for_build_wheel(config_settings=None):
    return []


get_requires_for_build_sdist = get_requires_for_build_editable = get_requires_for_build_wheel


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):
    name, version, meta = _metadata()
    dist = "%s-%s.dist-info" % (name, version)
    os.makedirs(os.path.join(metadata_directory, dist), exist_ok=True)
    with open(os.path.join(metadata_directory, dist, "METADATA"), "wb") as f:
        f.write(meta)
    return dist


prepare_metadata_for_build_editable = prepare_metadata_for_build_wheel


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    lib = _library()
    files = list(_sources())
    if lib:
        files.append(("cellar/libcellar.so.0", open(lib, "rb").read()))
    return _wheel(wheel_directory, files, lib)


def build_editable(wheel_directory, config_settings=None, metadata_directory=None):
    return _wheel(wheel_directory, [("cellar_editable.pth", (HERE + "\n").encode())], None)


def build_sdist(sdist_directory, config_settings=None):
    name, version, meta = _metadata()
    base = "%s-%s" % (name, version)
    fn = base + ".tar.gz"
    with tarfile.open(os.path.join(sdist_directory, fn), "w:gz", format=tarfile.PAX_FORMAT) as t:
        def add(arc, data):
            info = tarfile.TarInfo(base + "/" + arc)
            info.size, info.mode = len(data), 0o644
            t.addfile(info, io.BytesIO(data))
        for arc in ("pyproject.toml", "README.md", "_build/backend.py"):
            add(arc, open(os.path.join(HERE, arc), "rb").read())
        for arc, data in _sources():
            add(arc, data)
        add("PKG-INFO", meta)
    return fn
