"""Build times of the estimators' default patterns at counts no table holds (not a test).

For n in (34, 100, 200, 1000, 10^4, 10^5), disk (``vo_line`` / ``vo_area``) and ball
(``vo_point``), in one run:

- **cold**: ``vobscure.patterns.disk(n)`` / ``ball(n)`` in a fresh Python process (after
  ``import vobscure``): what the first estimator call of a session pays, the one-time tables
  of the relaxation (the disk's boundary force, the grids of the Voronoi diagrams) included;
- **warm**: the same pattern built again in this process with the per-process cache of the
  quick patterns bypassed (``vobscure.patterns.quick._quick.__wrapped__``), its peak traced
  memory (``tracemalloc``) beside it;
- what was built: the method, the refinement's step budget and steps taken, or the refusal.

A count above ``SAMPLES_LIMIT`` (65536) is refused: the row shows the time to refuse.

Run from the repository root: ``python benchmarks/bench_patterns.py``.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
import tracemalloc

from _bench import machine_facts

COUNTS = (34, 100, 200, 1000, 10 ** 4, 10 ** 5)

COLD = """
import json, sys, time
import vobscure.patterns as P
fn = P.disk if sys.argv[1] == "disk" else P.ball
t0 = time.perf_counter()
try:
    p = fn(int(sys.argv[2]))
    out = {"method": p.method, "refinement": p.provenance.get("refinement")}
except ValueError as e:
    out = {"refused": str(e)}
out["seconds"] = time.perf_counter() - t0
print(json.dumps(out))
"""


def cold(domain: str, n: int) -> dict:
    run = subprocess.run([sys.executable, "-c", COLD, domain, str(n)], capture_output=True, text=True, check=True)
    return json.loads(run.stdout.strip().splitlines()[-1])


def warm(domain: str, n: int) -> tuple[float, int]:
    from vobscure.patterns import SAMPLES_LIMIT
    from vobscure.patterns import quick as Q

    dim = 2 if domain == "disk" else 3
    if n > SAMPLES_LIMIT:
        return float("nan"), 0
    Q._quick.__wrapped__(dim, n, True, n % 2 == 1)           # the one-time tables
    tracemalloc.start()
    t0 = time.perf_counter()
    Q._quick.__wrapped__(dim, n, True, n % 2 == 1)
    seconds = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return seconds, peak


def main() -> int:
    machine_facts("OPENBLAS_NUM_THREADS should be 1; each cold build is a fresh process")
    print("== Build times of untabulated patterns (symmetric, the estimators' default)")
    print(f"  {'domain':6} {'n':>7} {'cold s':>8} {'warm s':>8} {'peak MB':>8}  built")
    for domain in ("disk", "ball"):
        for n in COUNTS:
            c = cold(domain, n)
            w, peak = warm(domain, n)
            if "refused" in c:
                built = "refused: " + c["refused"][:70] + "..."
            elif c["refinement"] is None:
                built = f"table entry ({c['method']}); warm: the quick pattern of the same n"
            else:
                r = c["refinement"]
                built = (f"{c['method']}, refinement skipped" if r["skipped"] else
                         f"{c['method']}, {r['steps_done']}/{r['steps_budget']} relaxation steps")
            print(f"  {domain:6} {n:>7} {c['seconds']:8.3f} {w:8.3f} {peak / 1e6:8.1f}  {built}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
