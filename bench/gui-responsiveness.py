#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""How long a workbench leaves its user waiting, measured as a user meets it.

Under a private Xvfb display, opens FILES in the application (scandiff, or
CloudCompare with --cloudcompare), answers the global-shift questions with
Return, waits until the resident memory stops growing (the files are read and
drawn), then drags the camera and clicks the File menu at several moments
after the drag, timing each click until the menu's window is on the screen.
Prints the resident memory and every menu time; saves a screenshot per app.

    bench/gui-responsiveness.py [--cloudcompare] [--label NAME] FILE...

Needs Xvfb, xdotool and ImageMagick's import (scripts/install-deps.sh).
"""
import argparse
import os
import subprocess
import sys
import time


def xdotool(display, *args):
    return subprocess.run(["xdotool", *args], env={**os.environ, "DISPLAY": display},
                          capture_output=True, text=True).stdout


def visible_windows(display, pid):
    return set(xdotool(display, "search", "--onlyvisible", "--pid", str(pid), "").split())


def resident_mb(pid):
    with open(f"/proc/{pid}/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return 0.0


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cloudcompare", action="store_true")
    parser.add_argument("--label", default="")
    parser.add_argument("--display", default=":71")
    parser.add_argument("--menu-at", default="", help="x,y of the File menu (default: scandiff's 20,12; CloudCompare's 37,10)")
    parser.add_argument("--settle", type=float, default=8.0, help="seconds of stable memory that mean 'loaded'")
    parser.add_argument("files", nargs="+")
    o = parser.parse_args()
    display = o.display
    menu_x, menu_y = (o.menu_at or ("37,10" if o.cloudcompare else "20,12")).split(",")
    xvfb = subprocess.Popen(["Xvfb", display, "-screen", "0", "1400x900x24"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(1)
    here = os.path.dirname(os.path.abspath(__file__))
    app = ["CloudCompare"] if o.cloudcompare else [os.path.join(here, "..", "build", "app", "gui", "scandiff")]
    env = {**os.environ, "DISPLAY": display}
    start = time.time()
    proc = subprocess.Popen(app + o.files, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    label = o.label or ("CloudCompare" if o.cloudcompare else "scandiff")
    try:
        # Loading: answer every question with Return; loaded when memory holds still.
        last, stable_since, peak = 0.0, time.time(), 0.0
        answered = set()
        while time.time() - stable_since < o.settle:
            time.sleep(0.5)
            rss = resident_mb(proc.pid)
            peak = max(peak, rss)
            questions = [w for w in xdotool(display, "search", "--onlyvisible", "--name", "[Ss]hift|Ply File Open").split() if w not in answered]
            if questions:  # the global-shift question (both applications ask it), PLY fields (CloudCompare): the default answer, once
                answered.add(questions[0])
                xdotool(display, "key", "Return")  # the dialog has the focus (no window manager here)
                stable_since = time.time()
            if abs(rss - last) > 20:
                stable_since = time.time()
            last = rss
        loaded = time.time() - start - o.settle
        print(f"{label}: loaded and drawn after about {loaded:.1f} s, resident {resident_mb(proc.pid):.0f} MB (peak seen {peak:.0f} MB)")
        subprocess.run(["import", "-window", "root", f"/tmp/gui-responsiveness-{label}.png"], env=env)
        resting = visible_windows(display, proc.pid)
        times = []
        for delay in [0.3, 0.6, 1.0, 2.0, 4.0]:
            # A camera drag across the middle of the view, then the File menu.
            xdotool(display, "mousemove", "650", "450", "mousedown", "1")
            for step in range(1, 8):
                xdotool(display, "mousemove", str(650 + 12 * step), str(450 + 4 * step))
                time.sleep(0.05)
            xdotool(display, "mouseup", "1")
            time.sleep(delay)
            clicked = time.time()
            xdotool(display, "mousemove", menu_x, menu_y, "click", "1")
            opened = None
            while time.time() - clicked < 120:
                if visible_windows(display, proc.pid) - resting:
                    opened = time.time() - clicked
                    break
                time.sleep(0.01)
            times.append(opened)
            xdotool(display, "key", "Escape")
            time.sleep(0.5)
            # Whatever the menu left behind (a queued click) is closed before the next round.
            for extra in visible_windows(display, proc.pid) - resting:
                xdotool(display, "key", "Escape")
            time.sleep(1.0)
        shown = ", ".join("none" if t is None else f"{t:.2f} s" for t in times)
        print(f"{label}: File menu {shown} (clicked 0.3, 0.6, 1, 2 and 4 s after a camera drag); longest "
              f"{max((t for t in times if t is not None), default=float('nan')):.2f} s; resident {resident_mb(proc.pid):.0f} MB")
    finally:
        proc.kill()
        xvfb.kill()


if __name__ == "__main__":
    sys.exit(main())
