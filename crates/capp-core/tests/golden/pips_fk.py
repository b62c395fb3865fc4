#!/usr/bin/env python3
"""Independent forward kinematics of PIPS (paper Table 1), for the golden test.

Written from the paper alone (eq. 5: A = Rot_z(theta) Trans_z(d) Trans_x(a) Rot_x(alpha),
T_k = T_{k-1} A_k), in float64 with plain lists: no code shared with the Rust crate.
Writes pips_fk.csv: one row per configuration, the 18 joint values (radians / inches),
then the 18 frame origins o_1..o_18 (x y z each, inches) and the end rotation (9 values,
row by row).

Regenerate:  python3 crates/capp-core/tests/golden/pips_fk.py > crates/capp-core/tests/golden/pips_fk.csv
"""
import math
import random

# alpha deg, theta deg, a in, d in, kind, min, max (deg or in): Table 1 and our limits.
TABLE = [
    (90, 90, 0, 22, "R", -180, 180),
    (90, 0, 0, 0, "R", -90, 90),
    (0, 0, -2.593, 20, "P", 10, 40),
    (0, -45, 0, 1, "P", 0, 30),
    (-90, 90, 0, 0, "P", -20, 20),
    (90, 0, 20, 0, "R", -60, 60),
    (-90, 0, 1.25, 0, "R", -60, 60),
    (90, 0, 20, 0, "R", -60, 60),
    (-90, 0, 16.003, 0, "R", -60, 60),
    (90, 0, 16.004, 0, "R", -60, 60),
    (-90, 0, 1.188, 0, "R", -60, 60),
    (90, 0, 16.004, 0, "R", -60, 60),
    (-90, 0, 12.006, 0, "R", -60, 60),
    (90, 0, 12.004, 0, "R", -60, 60),
    (-90, 0, 0.813, 0, "R", -60, 60),
    (90, 0, 12.004, 0, "R", -60, 60),
    (-90, 90, 0.833, -0.833, "R", 30, 150),
    (0, 45, 0, 1.793, "R", -180, 180),
]
D = math.pi / 180.0


def matmul(x, y):
    return [[sum(x[i][k] * y[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def dh(alpha, theta, a, d):
    ca, sa, ct, st = math.cos(alpha), math.sin(alpha), math.cos(theta), math.sin(theta)
    return [
        [ct, -st * ca, st * sa, a * ct],
        [st, ct * ca, -ct * sa, a * st],
        [0.0, sa, ca, d],
        [0.0, 0.0, 0.0, 1.0],
    ]


def fk(q):
    t = [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]
    origins = []
    for (alpha, theta, a, d, kind, _, _), v in zip(TABLE, q):
        if kind == "R":
            a_i = dh(alpha * D, v, a, d)
        else:
            a_i = dh(alpha * D, theta * D, a, v)
        t = matmul(t, a_i)
        origins.append((t[0][3], t[1][3], t[2][3]))
    rot = [t[i][j] for i in range(3) for j in range(3)]
    return origins, rot


def home():
    return [theta * D if kind == "R" else d for (_, theta, _, d, kind, _, _) in TABLE]


def main():
    rng = random.Random(1993)
    configs = [home()]
    for _ in range(40):
        q = []
        for (_, _, _, _, kind, lo, hi) in TABLE:
            v = rng.uniform(lo, hi)
            q.append(v * D if kind == "R" else v)
        configs.append(q)
    for q in configs:
        origins, rot = fk(q)
        row = list(q) + [c for o in origins for c in o] + rot
        print(",".join(repr(float(x)) for x in row))


if __name__ == "__main__":
    main()
