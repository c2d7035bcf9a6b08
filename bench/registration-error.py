#!/usr/bin/python3
"""The error of a registration matrix against the true one: the angle of the
residual rotation (degrees) and the largest displacement it gives a corner of
the synthetic site's box (60 x 60 x 12 m around the site's centre), in mm.
Usage: registration-error.py FOUND TRUTH [--shift SX,SY,SZ] [--centre X,Y,Z]
FOUND and TRUTH are 4 x 4 matrices as text (4 lines of 4 numbers; other
lines are skipped). --shift: FOUND acts on shifted coordinates, global +
shift (CloudCompare's -GLOBAL_SHIFT)."""
import math
import sys

import numpy as np


def read_matrix(path):
    rows = []
    with open(path) as f:
        for line in f:
            try:
                values = [float(v) for v in line.replace(",", " ").split()]
            except ValueError:
                continue
            if len(values) == 4:
                rows.append(values)
    if len(rows) < 4:
        sys.exit(f"{path}: no 4 x 4 matrix")
    return np.array(rows[-4:])


def option(name, default):
    if name in sys.argv:
        return np.array([float(v) for v in sys.argv[sys.argv.index(name) + 1].split(",")])
    return np.array(default)


found, truth = read_matrix(sys.argv[1]), read_matrix(sys.argv[2])
shift = option("--shift", [0.0, 0.0, 0.0])
centre = option("--centre", [512000.0, 5423000.0, 100.0])
to_shifted = np.eye(4)
to_shifted[:3, 3] = shift
found = np.linalg.inv(to_shifted) @ found @ to_shifted
delta = found @ np.linalg.inv(truth)
r = delta[:3, :3]
# From the sine (the skew part) and the cosine (the trace): exact for small angles too.
sine = 0.5 * np.linalg.norm([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
angle = math.degrees(math.atan2(sine, (np.trace(r) - 1) / 2))
worst = 0.0
for k in range(8):
    p = centre + np.array([30 if k & 1 else -30, 30 if k & 2 else -30, 12 if k & 4 else 0])
    q = delta[:3, :3] @ p + delta[:3, 3]
    worst = max(worst, float(np.linalg.norm(q - p)))
at_centre = float(np.linalg.norm(delta[:3, :3] @ centre + delta[:3, 3] - centre))
print(f"{angle:.6f} deg, {1000 * at_centre:.3f} mm at the centre, {1000 * worst:.3f} mm at worst")
