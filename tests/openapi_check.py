#!/usr/bin/env python3
"""openapi_check.py — every response a test got from cellard, checked against
schemas/openapi.json: the contract and the daemon agree.

Usage: python3 tests/openapi_check.py RESPONSES.jsonl...

Each line of a RESPONSES file is one exchange as tests/daemon.c records it:
  {"method": "POST", "path": "/v1/jobs?x=1", "status": 200,
   "headers": {"etag": "\"...\"", ...} (names lowercase), "body": "..." or null}
(body null: not recorded, as for a body over 256 KiB or one sent gzipped).  For each:
  - a path that matches no path of the spec must have answered 404 with a problem;
  - a method the path does not have: 405 with Allow (OPTIONS: 204 with Allow);
  - else the status must be one the operation lists (or its "default"); every header the
    response declares required must be there, and every declared header that is there must
    match its schema (pattern, integer); the Content-Type must be one the response lists, and a
    JSON body must validate against its schema (components resolved in the spec itself).
Prints "ok N responses" or one "FAIL ..." line per disagreement (at most 40), exits 1 on any.
"""
import json
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import validate  # noqa: E402  (tests/validate.py: strict JSON, the 4.10 / 4.18+ resolvers)

SPEC = validate.load_json(validate.OPENAPI)


def template_re(t):
    return re.compile("^" + re.sub(r"\\{[^}]+\\}", "[^/]+", re.escape(t)) + "$")


PATHS = [(template_re(t), t) for t in SPEC["paths"]]


def deref(o):
    while isinstance(o, dict) and "$ref" in o:
        ptr = o["$ref"]
        assert ptr.startswith("#/"), ptr
        o = SPEC
        for part in ptr[2:].split("/"):
            o = o[part.replace("~1", "/").replace("~0", "~")]
    return o


def schema_errors(schema, doc):
    """The most relevant error of doc against schema (a schema of the spec, its $refs into
    it), as a list of at most one message."""
    err = validate.first_error(validate.openapi_validator(SPEC, schema), doc)
    return [err] if err else []


def header_ok(spec_h, value):
    sch = deref(spec_h).get("schema", {})
    sch = deref(sch)
    if sch.get("type") == "integer":
        if not re.fullmatch(r"[0-9]+", value):
            return "not an integer: %r" % value
        return None
    pat = sch.get("pattern")
    if pat and not re.search(pat, value):
        return "%r does not match %s" % (value, pat)
    return None


def check(rec):
    method, status = rec["method"].upper(), rec["status"]
    path = rec["path"].split("?", 1)[0]
    headers = rec.get("headers") or {}
    where = "%s %s -> %d" % (method, rec["path"][:80], status)
    tmpl = next((t for r, t in PATHS if r.match(path)), None)
    if tmpl is None:
        return [] if status == 404 else ["%s: a path the spec does not have, not 404" % where]
    item = SPEC["paths"][tmpl]
    op = item.get("get" if method == "HEAD" else method.lower())
    if op is None:
        if method == "OPTIONS":
            return [] if status == 204 and "allow" in headers else [
                "%s: OPTIONS is 204 with Allow" % where]
        return [] if status == 405 and "allow" in headers else [
            "%s: a method the path does not have, not 405 with Allow" % where]
    responses = op.get("responses", {})
    resp = responses.get(str(status)) or responses.get("default")
    if resp is None:
        return ["%s: status %d is not one the operation lists (%s)" %
                (where, status, ", ".join(responses))]
    resp = deref(resp)
    errs = []
    for name, h in (resp.get("headers") or {}).items():
        value = headers.get(name.lower())
        if value is None:
            if deref(h).get("required"):
                errs.append("%s: the required header %s is missing" % (where, name))
            continue
        bad = header_ok(h, value)
        if bad:
            errs.append("%s: header %s: %s" % (where, name, bad))
    content = resp.get("content")
    ctype = headers.get("content-type", "").split(";")[0].strip()
    if content and method != "HEAD" and status not in (204, 304):
        listed = {k.split(";")[0].strip(): v for k, v in content.items()}
        if ctype not in listed:
            errs.append("%s: Content-Type %r, the spec lists %s" % (where, ctype, ", ".join(content)))
        elif rec.get("body") is not None and ctype.endswith("json"):
            sch = listed[ctype].get("schema")
            if sch is not None:
                try:
                    doc = validate.load_json_text(rec["body"])
                except ValueError as e:
                    errs.append("%s: the body is not JSON: %s" % (where, e))
                    doc = None
                if doc is not None:
                    for m in schema_errors(sch, doc)[:3]:
                        errs.append("%s: body: %s" % (where, m))
    return errs


def main(files):
    n, fails = 0, []
    for f in files:
        with open(f, encoding="utf-8") as fh:
            for line in fh:
                if not line.strip():
                    continue
                n += 1
                fails += check(json.loads(line))
    for m in fails[:40]:
        print("FAIL " + m)
    if len(fails) > 40:
        print("FAIL ... and %d more" % (len(fails) - 40))
    if not fails:
        print("ok %d responses" % n)
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
