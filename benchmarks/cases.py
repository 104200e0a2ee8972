"""The benchmark cases used by bench_time.py: the paper's base cases for the
8 control x slip x substrate combinations (d = 0.2 on the flat, where d = 0 is outside the domain)."""
from __future__ import annotations

import math

BASE = {"w": 0.2, "a_max": 0.25}
#: (label, control, slip, keyword arguments of adhfit.simulate)
CASES = [
    (f"{control} / {slip} / {sub}", control, slip,
     {**BASE, "rs": rs, **({"p": 0.6} if control == "displacement" else {"d": d})})
    for control in ("displacement", "pressure")
    for slip in ("frictionless", "no-slip")
    for sub, rs, d in (("rs=0.5", 0.5, 0.0), ("flat", math.inf, 0.2))
]
HEADLINE = "displacement / frictionless / rs=0.5"
