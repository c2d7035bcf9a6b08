#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Writes the points of channels7 and channels8 (see README.md) as text, for
`scandiff-cli convert` to write as LAS and LAZ: 2,000 points of a LAS 1.4 scan
whose four scanner channels come and go the ways a multi-channel scanner's
do (a channel first seen late, for one point, in runs, interleaved point by
point), with colours (and NIR), returns, GPS times, intensity,
classification and an Extra Bytes field. Usage: make-channel-samples.py DIR"""
import random
import sys


def channel(i, rng):
    if i < 100:
        return 0
    if i == 100:
        return 2                    # first seen, for one point
    if i < 300:
        return 0
    if i < 600:
        return 3 if i % 10 < 5 else 0  # runs of five
    if i < 1000:
        return (i // 3) % 2 * 2      # 0 and 2 in threes
    if i < 1500:
        return rng.randrange(4)      # channel 1 first seen here; point by point
    return (i // 5) % 4              # pulses of five


def main(out_dir):
    rng = random.Random(2026)
    for name, nir in (('channels7', False), ('channels8', True)):
        lines = []
        time = 412345.0
        x = 651000.0
        for i in range(2000):
            returns = 1 + (i // 3) % 3
            ret = 1 + i % returns
            if ret == 1:
                time += 0.0001
            x += rng.uniform(0.0, 0.05)
            grey = rng.randrange(256)
            rgb = (grey, grey, grey) if i % 7 == 0 else (rng.randrange(256), rng.randrange(256), rng.randrange(256))
            row = [f'{x:.3f}', f'{6862000 + rng.uniform(0, 30):.3f}', f'{120 + rng.uniform(0, 5):.3f}',
                   *map(str, rgb)]
            if nir:
                row.append(str(rng.randrange(65536)))
            row += [str(channel(i, rng)), str(ret), str(returns), f'{time:.6f}', str(rng.randrange(4000)),
                    str(rng.choice((2, 3, 5, 6))), str(rng.randrange(300))]
            lines.append(' '.join(row))
        with open(f'{out_dir}/{name}.txt', 'w') as out:
            out.write('\n'.join(lines) + '\n')
        columns = 'x,y,z,r,g,b' + (',nir' if nir else '') + \
                  ',scanner_channel,return_number,number_of_returns,gps_time,intensity,classification,amplitude'
        with open(f'{out_dir}/{name}.columns', 'w') as out:
            out.write(columns + '\n')


if __name__ == '__main__':
    main(sys.argv[1])
