#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Interoperability sweep of scandiff's LAZ against laz-perf: for each seed,
random points (point format 6, 7 or 8; 1 to 120,000 points, so chunk borders
at 50,000 are crossed; any subset of the LAS 1.4 attributes; 0 to 5 Extra
Bytes fields; scanner channels fixed, random point by point, in runs, or
appearing halfway) are written by scandiff as LAS and as LAZ, and laz-perf
must decode the LAZ into records equal byte for byte to the LAS file's.
Prints one line per seed; exits 1 if any differs.
Usage: laz-peer-sweep.py SCANDIFF_CLI WORK_DIR FIRST_SEED END_SEED
(run by bench/run-laz-peer.sh, which fetches laz-perf)"""
import os
import random
import struct
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
OPTIONAL = ['intensity', 'return_number', 'number_of_returns', 'gps_time', 'classification', 'user_data',
            'scan_angle', 'point_source_id', 'classification_flags', 'scan_direction_flag',
            'edge_of_flight_line', 'scanner_channel']


def points(rng):
    """The columns and the text rows of one case."""
    count = rng.choice([1, 2, 3, 17, 1000, 49999, 50000, 50001, 120000])
    columns = ['x', 'y', 'z']
    point_format = rng.choice([6, 7, 8])
    if point_format >= 7:
        columns += ['r', 'g', 'b']
    if point_format == 8:
        columns += ['nir']
    columns += [c for c in OPTIONAL if rng.random() < 0.6]
    columns += [f'extra{i}' for i in range(rng.choice([0, 0, 1, 2, 5]))]
    channels = rng.choice(['fixed', 'random', 'runs', 'halfway'])
    time, x = 300000.0, 651000.0
    rows = []
    for i in range(count):
        returns = rng.randint(1, 5)
        number = rng.randint(1, returns)
        if rng.random() < 0.7:
            time += rng.choice([0, 1e-5, 2e-5, 0.25, 13.0])
        x += rng.uniform(0, 0.03)
        value = {
            'x': lambda: f'{x:.3f}', 'y': lambda: f'{6862000 + rng.uniform(0, 50):.3f}',
            'z': lambda: f'{rng.uniform(100, 130):.3f}', 'r': lambda: str(rng.randrange(256)),
            'g': lambda: str(rng.randrange(256)), 'b': lambda: str(rng.randrange(256)),
            'nir': lambda: str(rng.randrange(65536)), 'intensity': lambda: str(rng.randrange(65536)),
            'return_number': lambda: str(number), 'number_of_returns': lambda: str(returns),
            'gps_time': lambda: f'{time:.6f}',
            'classification': lambda: str(rng.choice([1, 2, 3, 5, 6, 7, 9, 17, 64, 255])),
            'user_data': lambda: str(rng.randrange(256)),
            'scan_angle': lambda: f'{round(rng.uniform(-30, 30) / 0.006) * 0.006:.3f}',
            'point_source_id': lambda: str(rng.choice([1, 2, 700, 65535])),
            'classification_flags': lambda: str(rng.randrange(16)),
            'scan_direction_flag': lambda: str(rng.randrange(2)), 'edge_of_flight_line': lambda: str(rng.randrange(2)),
            'scanner_channel': lambda: str({'fixed': 2, 'random': rng.randrange(4), 'runs': (i // 7) % 4,
                                            'halfway': 0 if i < count // 2 else rng.randrange(4)}[channels]),
        }
        rows.append(' '.join(value[c]() if c in value else f'{rng.uniform(-1000, 1000):.3f}' for c in columns))
    return columns, rows, channels


def check(cli, work, seed):
    rng = random.Random(seed)
    columns, rows, channels = points(rng)
    text, las_path, laz_path, records = (os.path.join(work, f) for f in ('case.txt', 'case.las', 'case.laz', 'case.rec'))
    with open(text, 'w') as out:
        out.write('\n'.join(rows) + '\n')
    for path in (las_path, laz_path):
        subprocess.run([cli, 'convert', '--columns', ','.join(columns), '--separator', 'space', text, path],
                       check=True, capture_output=True)
    subprocess.run(['node', os.path.join(HERE, 'laz-perf-decode.mjs'), laz_path, records], check=True, capture_output=True)
    with open(las_path, 'rb') as f:
        las = f.read()
    with open(records, 'rb') as f:
        decoded = f.read()
    start, = struct.unpack_from('<I', las, 96)
    length, = struct.unpack_from('<H', las, 105)
    ours = las[start:start + len(rows) * length]
    what = f'format {las[104] & 63}, {length}-byte records, {len(rows)} points, channels {channels}: {",".join(columns)}'
    if ours == decoded:
        return True, what
    first = next((i for i in range(len(rows)) if ours[i * length:(i + 1) * length] != decoded[i * length:(i + 1) * length]),
                 len(rows))
    return False, f'{what}: laz-perf parts from the LAS twin at record {first}'


def main():
    cli, work, first, end = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    failures = 0
    for seed in range(first, end):
        same, what = check(cli, work, seed)
        print(f'seed {seed}: {"same records" if same else "DIFFERENT"}, {what}', flush=True)
        failures += not same
    sys.exit(1 if failures else 0)


if __name__ == '__main__':
    main()
