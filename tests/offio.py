"""offio.py — reading OFF files for the Python tests and the benchmark's inputs
(tests/real3d.py, tests/winding3d.py and bench/gen3d.py import it: the tests run as
`python3 tests/NAME.py`, so this directory is on their path; gen3d.py puts it there).

read_off(path) returns (V, F): the vertices as [x, y, z] lists and the faces as lists of vertex
indices; '#' starts a comment.  A file whose first word does not end in "OFF" is a ValueError.
"""


def read_off(path):
    d = [t for line in open(path) for t in line.split("#")[0].split()]
    if not d or not d[0].endswith("OFF"):
        raise ValueError("%s: not an OFF file" % path)
    nv, nf = int(d[1]), int(d[2])
    q = 4
    V, Fc = [], []
    for _ in range(nv):
        V.append([float(d[q]), float(d[q + 1]), float(d[q + 2])])
        q += 3
    for _ in range(nf):
        n = int(d[q])
        Fc.append([int(x) for x in d[q + 1:q + 1 + n]])
        q += 1 + n
    return V, Fc
