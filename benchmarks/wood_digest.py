"""Digests of grown wood maps, to show a speed change leaves the maps byte for byte as they were.

Prints one JSON object: for each case, the number of darts and a sha256 (first 16 hex digits) of
alpha and of every dart and volume column (its bytes and dtype).  Run it on the code before and
after a change and compare the two outputs (``diff``)::

    python benchmarks/wood_digest.py > before.json      # on the old code
    python benchmarks/wood_digest.py > after.json
    diff before.json after.json && echo same

``--large`` adds the 30-year, 20-branch pine of ``bench_wood.py`` (2.8 million darts, a few
seconds); ``--every-step`` grows the cases with the embedding and the checks after every step
(the kernel's incremental paths).
"""

from __future__ import annotations

import argparse
import hashlib
import json

import numpy as np

from ramure.gmap import GMap3
from ramure.gmap.organs import wood as W

CASES = [("pine", 3, 2), ("pine", 8, 5), ("oak", 5, 3)]
LARGE = ("pine", 30, 20)


def _sha(arr: np.ndarray) -> str:
    arr = np.ascontiguousarray(arr)
    return hashlib.sha256(arr.tobytes() + str(arr.dtype).encode()).hexdigest()[:16]


def map_digest(gm: GMap3) -> dict[str, object]:
    """``{"n_darts": ..., "alpha": sha, "d:<column>": sha, "v:<column>": sha}`` of a map."""
    out: dict[str, object] = {"n_darts": gm.n_darts, "alpha": _sha(gm.alpha.astype(np.int64))}
    out.update({f"d:{name}": _sha(col) for name, col in sorted(gm.dart_data.items())})
    out.update({f"v:{name}": _sha(col) for name, col in sorted(gm.volume_data.items())})
    return out


def main(argv: list[str] | None = None) -> None:
    """Print the digests of the cases (see the module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--large", action="store_true", help="add the 30-year, 20-branch pine")
    parser.add_argument("--every-step", action="store_true", help="embed and check after every step")
    args = parser.parse_args(argv)
    cases = CASES + ([LARGE] if args.large else [])
    out = {}
    for species, years, branches in cases:
        w = W.grow_wood(
            species, years=years, branches=branches, embed_every_step=args.every_step, check_every_step=args.every_step
        )
        out[f"{species}-{years}-{branches}"] = map_digest(w.gm)
    print(json.dumps(out, indent=1, sort_keys=True))


if __name__ == "__main__":
    main()
