#!/usr/bin/env python3
"""validate.py — validates JSON documents against cellar's JSON Schemas (draft 2020-12).

Usage:
  python3 tests/validate.py NAME FILE...     each FILE ("-": stdin) against schemas/NAME.schema.json
                                             (request, result, problem, job); NAME may also be
                                             openapi:COMPONENT, a schema of schemas/openapi.json
                                             (e.g. openapi:Result), as a client would read it
  python3 tests/validate.py --check-all      every schema of schemas/ and schemas/openapi.json
  python3 tests/validate.py --write-openapi  regenerates components/schemas of schemas/openapi.json

Prints one line per file ("ok NAME FILE" or "FAIL NAME FILE: PATH: MESSAGE") or per check, and
exits 1 when anything is invalid (2 on a usage error).

The documents are read as strict JSON: NaN, Infinity and duplicate keys are refused, as the
service refuses them.  The "format" keyword is left an annotation (the default of draft 2020-12):
whether it is checked would depend on optional Python packages, so the schemas say what matters
with "pattern" instead and a result never depends on the machine.

schemas/openapi.json is one self-contained file (the daemon embeds it).  Its components/schemas
are generated from the schema files by --write-openapi: each file becomes the component named
by its "title", each of its $defs the component named by the def's "title", and every $ref is
rewritten to "#/components/schemas/...".  --check-all fails when they have drifted apart, so
edit the schema files and regenerate; the rest of openapi.json (paths, parameters, headers,
responses, examples) is written by hand.

Works with Debian 12's python3-jsonschema (4.10, RefResolver) and with newer releases
(4.18 and later, the referencing registry).
"""
import copy
import json
import os
import re
import sys
import urllib.parse
import warnings

import jsonschema
from jsonschema import Draft202012Validator
from jsonschema.exceptions import relevance

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCHEMA_DIR = os.path.join(ROOT, "schemas")
OPENAPI = os.path.join(SCHEMA_DIR, "openapi.json")
DIALECT = "https://json-schema.org/draft/2020-12/schema"
ID_BASE = "https://cellar.invalid/schemas/"
SCHEMA_ORDER = ["request", "result", "problem", "job"]  # component order in openapi.json
MSG_MAX = 240


# ---------------------------------------------------------------------------- strict JSON


def _no_constant(name):
    raise ValueError("%s is not JSON" % name)


def _no_duplicates(pairs):
    obj = {}
    for k, v in pairs:
        if k in obj:
            raise ValueError("duplicate key %r" % k)
        obj[k] = v
    return obj


def load_json_text(text):
    return json.loads(text, parse_constant=_no_constant, object_pairs_hook=_no_duplicates)


def load_json(path):
    if path == "-":
        data = sys.stdin.buffer.read()
    else:
        with open(path, "rb") as f:
            data = f.read()
    return load_json_text(data.decode("utf-8"))


# ---------------------------------------------------------------------------- schemas


def schema_files():
    """{name: path} of schemas/*.schema.json."""
    out = {}
    for fn in sorted(os.listdir(SCHEMA_DIR)):
        if fn.endswith(".schema.json"):
            out[fn[: -len(".schema.json")]] = os.path.join(SCHEMA_DIR, fn)
    return out


def load_schemas():
    """({name: schema}, {$id: schema})."""
    by_name, by_id = {}, {}
    for name, path in schema_files().items():
        s = load_json(path)
        by_name[name] = s
        if isinstance(s, dict) and isinstance(s.get("$id"), str):
            by_id[s["$id"]] = s
    return by_name, by_id


def make_validator(schema, store):
    """A Draft202012Validator for schema that resolves $refs to the schemas of store
    ({$id: schema}) and never goes to the network."""
    try:
        import referencing
        import referencing.jsonschema
    except ImportError:
        referencing = None
    if referencing is not None:
        spec = referencing.jsonschema.DRAFT202012
        registry = referencing.Registry().with_resources(
            (uri, referencing.Resource.from_contents(s, default_specification=spec))
            for uri, s in store.items()
        )
        return Draft202012Validator(schema, registry=registry)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        resolver = jsonschema.RefResolver.from_schema(schema, store=dict(store))
    return Draft202012Validator(schema, resolver=resolver)


def json_path(parts):
    """The API's JSON path notation: lines[17][1], options.precision."""
    out = ""
    for p in parts:
        if isinstance(p, int):
            out += "[%d]" % p
        else:
            out += ("." if out else "") + str(p)
    return out


def first_error(validator, doc):
    """None, or "PATH: MESSAGE" of the most relevant error."""
    errors = list(validator.iter_errors(doc))
    if not errors:
        return None
    # the top error as best_match chooses it; below a oneOf (whose branch may have failed in
    # several places at once: a stats object missing two keys) the deepest leaf names the
    # offending input best
    err = max(errors, key=relevance)
    while err.context:
        ctx = err.context
        # a oneOf over request kinds: leave out the branches of the other kinds (those whose
        # "kind" const fails), unless no branch is left (an unknown kind)
        wrong = {e.relative_schema_path[0] for e in ctx
                 if e.validator == "const" and list(e.relative_path) == ["kind"] and e.relative_schema_path}
        rest = [e for e in ctx if not e.relative_schema_path or e.relative_schema_path[0] not in wrong]
        err = max(rest or ctx, key=lambda e: len(e.absolute_path))
    msg = " ".join(err.message.split())
    if len(msg) > MSG_MAX:
        msg = msg[: MSG_MAX - 3] + "..."
    return "%s: %s" % (json_path(err.absolute_path) or "(document)", msg)


# ---------------------------------------------------------------------------- openapi


def camel(name):
    return "".join(w[:1].upper() + w[1:] for w in re.split(r"[_\W]+", name) if w)


def component_names(by_name):
    """{(name, def or None): component name}."""
    names = {}
    for name, s in by_name.items():
        names[(name, None)] = s.get("title") or camel(name)
        for d, sub in s.get("$defs", {}).items():
            names[(name, d)] = sub.get("title") or camel(d)
    return names


def rewrite_ref(ref, base_id, ids, names):
    """The openapi.json form of ref, a $ref found in the schema whose $id is base_id."""
    full = urllib.parse.urljoin(base_id, ref)
    uri, frag = urllib.parse.urldefrag(full)
    if uri not in ids:
        raise ValueError("$ref %r: no schema has $id %r" % (ref, uri))
    name = ids[uri]
    segs = frag.split("/")[1:] if frag else []
    if len(segs) >= 2 and segs[0] == "$defs":
        target = names[(name, segs[1])]
        rest = segs[2:]
    else:
        target = names[(name, None)]
        rest = segs
    return "#/components/schemas/" + "/".join([target] + rest)


def _rewrite(node, base_id, ids, names):
    if isinstance(node, dict):
        out = {}
        for k, v in node.items():
            if k == "$ref" and isinstance(v, str):
                out[k] = rewrite_ref(v, base_id, ids, names)
            elif k == "discriminator" and isinstance(v, dict):
                d = copy.deepcopy(v)
                for mk, mv in d.get("mapping", {}).items():
                    d["mapping"][mk] = rewrite_ref(mv, base_id, ids, names)
                out[k] = d
            else:
                out[k] = _rewrite(v, base_id, ids, names)
        return out
    if isinstance(node, list):
        return [_rewrite(v, base_id, ids, names) for v in node]
    return node


def openapi_components(by_name):
    """The components/schemas that openapi.json must hold, generated from the schema files."""
    names = component_names(by_name)
    seen = {}
    for key, comp in names.items():
        if comp in seen:
            raise ValueError("component name %r used by %r and %r" % (comp, seen[comp], key))
        seen[comp] = key
    ids = {s["$id"]: name for name, s in by_name.items()}
    order = [n for n in SCHEMA_ORDER if n in by_name] + sorted(set(by_name) - set(SCHEMA_ORDER))
    out = {}
    for name in order:
        s = by_name[name]
        base = s["$id"]
        top = {k: v for k, v in s.items() if k not in ("$schema", "$id", "$defs")}
        out[names[(name, None)]] = _rewrite(top, base, ids, names)
        for d, sub in s.get("$defs", {}).items():
            out[names[(name, d)]] = _rewrite(sub, base, ids, names)
    return out


def dumps_pretty(node, indent=0):
    """JSON with 2-space indentation, short arrays and objects of scalars on one line."""
    pad = "  " * indent
    flat = json.dumps(node, ensure_ascii=False)
    if not isinstance(node, (dict, list)) or not node:
        return flat
    scalars = all(not isinstance(v, (dict, list)) for v in (node.values() if isinstance(node, dict) else node))
    if (scalars or isinstance(node, list)) and len(flat) + len(pad) <= 100:
        return flat
    inner = "  " * (indent + 1)
    if isinstance(node, dict):
        items = ["%s%s: %s" % (inner, json.dumps(k, ensure_ascii=False), dumps_pretty(v, indent + 1)) for k, v in node.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    items = [inner + dumps_pretty(v, indent + 1) for v in node]
    return "[\n" + ",\n".join(items) + "\n" + pad + "]"


def write_openapi():
    by_name, _ = load_schemas()
    doc = load_json(OPENAPI)
    doc.setdefault("components", {})["schemas"] = openapi_components(by_name)
    text = dumps_pretty(doc) + "\n"
    with open(OPENAPI, "w", encoding="utf-8") as f:
        f.write(text)
    print("wrote %s (%d schemas)" % (os.path.relpath(OPENAPI), len(doc["components"]["schemas"])))
    return 0


def resolve_pointer(doc, ref):
    """The node of doc at the local reference ref ("#/a/b"); KeyError when there is none."""
    if not ref.startswith("#"):
        raise KeyError("not a local reference")
    node = doc
    frag = urllib.parse.unquote(ref[1:])
    for seg in frag.split("/")[1:] if frag else []:
        seg = seg.replace("~1", "/").replace("~0", "~")
        if isinstance(node, list):
            node = node[int(seg)]
        elif isinstance(node, dict):
            node = node[seg]
        else:
            raise KeyError(seg)
    return node


def walk(node, path=()):
    """Yields (path, dict) for every object in node."""
    if isinstance(node, dict):
        yield path, node
        for k, v in node.items():
            yield from walk(v, path + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from walk(v, path + (i,))


def openapi_validator(doc, schema):
    """A validator of schema (a schema of doc, whose $refs point into doc)."""
    wrapper = {"$schema": DIALECT, "components": doc.get("components", {}), "allOf": [schema]}
    return make_validator(wrapper, {})


def component_validator(doc, name):
    schemas = doc.get("components", {}).get("schemas", {})
    if name not in schemas:
        raise KeyError("openapi.json has no components/schemas/%s" % name)
    return openapi_validator(doc, {"$ref": "#/components/schemas/" + name})


# ---------------------------------------------------------------------------- checks


class Report:
    def __init__(self):
        self.failed = 0

    def check(self, ok, what, why=""):
        if ok:
            print("ok %s" % what)
        else:
            self.failed += 1
            print("FAIL %s%s" % (what, ": " + why if why else ""))
        return ok


def lint_schema(name, s):
    """Problems of style: $schema, $id, titles of $defs, a description on every property."""
    problems = []
    if s.get("$schema") != DIALECT:
        problems.append("$schema is not %s" % DIALECT)
    if s.get("$id") != ID_BASE + name + ".schema.json":
        problems.append("$id is not %s%s.schema.json" % (ID_BASE, name))
    for key in ("title", "description"):
        if not s.get(key):
            problems.append("no %s" % key)
    for d, sub in s.get("$defs", {}).items():
        if not isinstance(sub, dict) or not sub.get("title") or not sub.get("description"):
            problems.append("$defs/%s: needs a title and a description" % d)
        elif "$defs" in sub:
            problems.append("$defs/%s: nested $defs (openapi.json could not name them)" % d)

    def props(node, path, conditional):
        if isinstance(node, dict):
            for k, v in node.items():
                cond = conditional or k in ("if", "then", "else", "not")
                if k == "properties" and isinstance(v, dict):
                    # a map of property names to schemas: a property may itself be named
                    # "properties" (a layer's), so each schema is walked as a schema
                    for p, sub in v.items():
                        if not conditional and (not isinstance(sub, dict) or not sub.get("description")):
                            problems.append("%s/properties/%s: no description" % ("/".join(path) or "#", p))
                        props(sub, path + ("properties", str(p)), cond)
                    continue
                props(v, path + (str(k),), cond)
        elif isinstance(node, list):
            for i, v in enumerate(node):
                props(v, path + (str(i),), conditional)

    props(s, (), False)
    return problems


def local_refs_resolve(doc, base_id, by_id):
    """$refs (and discriminator mappings) of a schema file that do not resolve."""
    bad = []
    for path, node in walk(doc):
        refs = []
        if isinstance(node.get("$ref"), str):
            refs.append(node["$ref"])
        if path and path[-1] == "discriminator" and isinstance(node.get("mapping"), dict):
            refs += [v for v in node["mapping"].values()]
        for ref in refs:
            full = urllib.parse.urljoin(base_id, ref)
            uri, frag = urllib.parse.urldefrag(full)
            target = by_id.get(uri)
            try:
                if target is None:
                    raise KeyError(uri)
                resolve_pointer(target, "#" + frag)
            except (KeyError, IndexError, ValueError):
                bad.append(ref)
    return bad


def check_all():
    r = Report()
    try:
        by_name, by_id = load_schemas()
    except (OSError, ValueError) as e:
        r.check(False, "schemas/*.schema.json are JSON", str(e))
        return 1
    r.check(set(SCHEMA_ORDER) <= set(by_name), "schemas/ has %s" % ", ".join(SCHEMA_ORDER),
            "missing " + ", ".join(sorted(set(SCHEMA_ORDER) - set(by_name))))
    for name, s in by_name.items():
        where = "schemas/%s.schema.json" % name
        try:
            Draft202012Validator.check_schema(s)
            r.check(True, "%s is a valid draft 2020-12 schema" % where)
        except jsonschema.exceptions.SchemaError as e:
            r.check(False, "%s is a valid draft 2020-12 schema" % where, " ".join(e.message.split())[:MSG_MAX])
            continue
        problems = lint_schema(name, s)
        r.check(not problems, "%s: $schema, $id, titles, descriptions" % where, "; ".join(problems[:5]))
        bad = local_refs_resolve(s, s.get("$id", ""), by_id)
        r.check(not bad, "%s: every $ref resolves" % where, ", ".join(bad[:5]))

    where = "schemas/openapi.json"
    try:
        doc = load_json(OPENAPI)
    except (OSError, ValueError) as e:
        r.check(False, "%s is JSON" % where, str(e))
        return 1
    r.check(True, "%s is JSON" % where)
    r.check(doc.get("openapi") == "3.1.0", "%s: openapi 3.1.0" % where, "openapi is %r" % doc.get("openapi"))
    bad = []
    for path, node in walk(doc):
        refs = [node["$ref"]] if isinstance(node.get("$ref"), str) else []
        if path and path[-1] == "discriminator" and isinstance(node.get("mapping"), dict):
            refs += list(node["mapping"].values())
        for ref in refs:
            try:
                resolve_pointer(doc, ref)
            except (KeyError, IndexError, ValueError):
                bad.append("%s at %s" % (ref, "/".join(map(str, path))))
    r.check(not bad, "%s: every $ref resolves inside the document" % where, "; ".join(bad[:5]))

    comps = doc.get("components", {}).get("schemas", {})
    errs = []
    for cname, cs in comps.items():
        try:
            Draft202012Validator.check_schema(cs)
        except jsonschema.exceptions.SchemaError as e:
            errs.append("%s: %s" % (cname, " ".join(e.message.split())[:120]))
    r.check(bool(comps) and not errs, "%s: components/schemas are valid draft 2020-12 schemas (%d)" % (where, len(comps)),
            "; ".join(errs[:3]) or "none")
    try:
        want = openapi_components(by_name)
        drift = sorted(set(want) ^ set(comps)) + sorted(k for k in want if k in comps and want[k] != comps[k])
        r.check(not drift, "%s: components/schemas match the schema files" % where,
                "differ: %s (run python3 tests/validate.py --write-openapi)" % ", ".join(drift[:8]))
    except (KeyError, ValueError) as e:
        r.check(False, "%s: components/schemas match the schema files" % where, str(e))

    ops = []
    for p, item in doc.get("paths", {}).items():
        for m in ("get", "put", "post", "delete", "patch", "head", "options", "trace"):
            if m in item:
                ops.append((p, m, item[m]))
    ids = [op.get("operationId") for _, _, op in ops]
    r.check(len(ops) > 0 and None not in ids and len(set(ids)) == len(ids),
            "%s: %d operations, each with a unique operationId" % (where, len(ops)), "operationIds: %r" % ids)
    noresp = ["%s %s" % (m.upper(), p) for p, m, op in ops if not op.get("responses")]
    r.check(not noresp, "%s: every operation has responses" % where, ", ".join(noresp))

    # every example against its schema, through openapi.json's own components
    nex, exerr = 0, []
    for path, node in walk(doc):
        if "schema" not in node or not isinstance(node["schema"], dict):
            continue
        values = []
        if "example" in node:
            values.append(("example", node["example"]))
        for en, ex in node.get("examples", {}).items() if isinstance(node.get("examples"), dict) else []:
            try:
                ex = resolve_pointer(doc, ex["$ref"]) if "$ref" in ex else ex
                values.append((en, ex["value"]))
            except (KeyError, IndexError, ValueError):
                exerr.append("%s/examples/%s: unresolved" % ("/".join(map(str, path)), en))
        if not values:
            continue
        v = openapi_validator(doc, node["schema"])
        for en, value in values:
            nex += 1
            e = first_error(v, value)
            if e:
                exerr.append("%s (%s): %s" % ("/".join(map(str, path)), en, e))
    r.check(nex > 0 and not exerr, "%s: %d examples match their schemas" % (where, nex), "; ".join(exerr[:3]))
    return 1 if r.failed else 0


def validate_files(name, files):
    try:
        if name.startswith("openapi:"):
            doc = load_json(OPENAPI)
            validator = component_validator(doc, name[len("openapi:"):])
            Draft202012Validator.check_schema(doc["components"]["schemas"][name[len("openapi:"):]])
        else:
            by_name, by_id = load_schemas()
            if name not in by_name:
                print("validate.py: no schema %r (have: %s)" % (name, ", ".join(sorted(by_name))), file=sys.stderr)
                return 2
            Draft202012Validator.check_schema(by_name[name])
            validator = make_validator(by_name[name], by_id)
    except jsonschema.exceptions.SchemaError as e:
        print("FAIL %s: the schema itself is invalid: %s" % (name, " ".join(e.message.split())[:MSG_MAX]))
        return 1
    except (OSError, ValueError, KeyError) as e:
        print("FAIL %s: cannot load the schema: %s" % (name, e))
        return 1
    failed = 0
    for f in files:
        try:
            doc = load_json(f)
        except (OSError, ValueError) as e:
            failed += 1
            print("FAIL %s %s: not JSON: %s" % (name, f, " ".join(str(e).split())[:MSG_MAX]))
            continue
        e = first_error(validator, doc)
        if e is None:
            print("ok %s %s" % (name, f))
        else:
            failed += 1
            print("FAIL %s %s: %s" % (name, f, e))
    return 1 if failed else 0


def main(argv):
    if len(argv) == 1 and argv[0] == "--check-all":
        return check_all()
    if len(argv) == 1 and argv[0] == "--write-openapi":
        return write_openapi()
    if len(argv) >= 2 and not argv[0].startswith("-"):
        return validate_files(argv[0], argv[1:])
    print(__doc__.split("\n\n")[1], file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
