"""tally.py — the counts of the Python tests' checks (tests/*.py import it: they run as
`python3 tests/NAME.py`, so this directory is on their path).

ok(name) and fail(name, why) print one line each ("ok NAME" / "FAIL NAME: WHY"); summary()
prints the "N passed, N failed" line that tests/run.sh adds up and returns the exit status.
"""

passed = 0
failed = 0


def ok(name):
    global passed
    passed += 1
    print("ok", name)


def fail(name, why=""):
    global failed
    failed += 1
    print("FAIL", name + (": " + why if why else ""))


def summary():
    print("%d passed, %d failed" % (passed, failed))
    return 1 if failed else 0
