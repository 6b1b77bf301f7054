#!/usr/bin/python3
"""Byte-for-byte comparison of trajectories run before and after a refactor (STYLE: a refactor keeps
behaviour, shown by identical trajectories).

    identical_trajectories.py BEFORE_DIR AFTER_DIR [--added PATH ...]

For every trajectory BEFORE_DIR/*.h5 that AFTER_DIR also has: every dataset's dtype, shape and bytes and
every attribute, group by group, with /provenance left out (tool version, command line, input hashes:
they differ by design). Prints one line per pair, the first differences of a pair that differs; exits 1
when any pair differs or none was found. --added PATH (e.g. /trajectory/tools/sphere_loads): a dataset the
change adds on purpose; its presence after alone is listed, not counted as a difference. Needs h5py and numpy (Debian python3-h5py).
bench/bundled_trajectories.sh runs every bundled scenario into such a folder.
"""
import pathlib
import sys

import h5py
import numpy as np


ADDED = set()


def differences(a, b, path=""):
    out = []
    for k, v in a.attrs.items():
        if k not in b.attrs:
            out.append(f"{path}@{k}: missing after")
        elif np.asarray(v).tobytes() != np.asarray(b.attrs[k]).tobytes() or np.asarray(v).dtype != np.asarray(b.attrs[k]).dtype:
            out.append(f"{path}@{k}: {v!r} != {b.attrs[k]!r}")
    out += [f"{path}@{k}: missing before" for k in b.attrs if k not in a.attrs]
    for k in a:
        p = f"{path}/{k}"
        if p == "/provenance":
            continue
        if k not in b:
            out.append(f"{p}: missing after")
        elif isinstance(a[k], h5py.Group):
            out += differences(a[k], b[k], p)
        else:
            da, db = np.asarray(a[k][()]), np.asarray(b[k][()])
            if da.dtype != db.dtype or da.shape != db.shape or da.tobytes() != db.tobytes():
                out.append(f"{p}: data differ ({da.dtype}{da.shape} vs {db.dtype}{db.shape})")
            out += differences(a[k], b[k], p) if a[k].attrs else []
    out += [f"{path}/{k}: missing before" for k in b if k not in a and f"{path}/{k}" != "/provenance" and f"{path}/{k}" not in ADDED]
    return out


def main():
    args = sys.argv[1:]
    while "--added" in args:
        i = args.index("--added")
        if i + 1 >= len(args):
            sys.exit(__doc__)
        ADDED.add(args[i + 1])
        del args[i:i + 2]
    if len(args) != 2:
        sys.exit(__doc__)
    before, after = pathlib.Path(args[0]), pathlib.Path(args[1])
    pairs = [(p, after / p.name) for p in sorted(before.glob("*.h5")) if (after / p.name).exists()]
    if not pairs:
        sys.exit(f"no trajectory in both {before} and {after}")
    differ = 0
    for a, b in pairs:
        with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
            d = differences(fa, fb)
        with h5py.File(b, "r") as fb:
            added = [p for p in sorted(ADDED) if p in fb]
        print(f"{a.name}: {'identical' if not d else 'DIFFER'}{' (added: ' + ', '.join(added) + ')' if added and not d else ''}")
        for line in d[:10]:
            print(f"  {line}")
        differ += bool(d)
    print(f"{len(pairs) - differ} identical, {differ} differ")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
