#!/usr/bin/env python3
"""Writes assets/hands/aggressive.csv: a hand that hits the water of assets/scenes/hand_tank.json as hard as the
mouse hand can (input/mouse_hand.h: maxSpeed 2.5 m/s), for the soak tests (tests/test_soak.cpp).

One 6-second cycle, in this order:
  1. three sweeps back and forth along x through the water, flat hand, at exactly 2.5 m/s, the palm turned to
     face the way it moves (palm 20 cm above the floor: the fingers reach 9 cm deep);
  2. two sweeps along z, palm turned to face z;
  3. three fist slams (grip 1): from 16 cm above the surface straight down to 5 cm above the floor at 2.5 m/s,
     and straight back up;
  4. lift out and plunge: the flat hand held 25 cm above the water, then plunged at 2.5 m/s to 4 cm above the
     floor, held under water, pulled out at 2.5 m/s;
  5. the point gesture (grip 1, point 1): two circles of 8 cm radius stirred at 2.5 m/s, then back to flat.
Every segment moves at most 2.5 m/s (checked here); gestures change at most at the animator's rate (full range
in 0.25 s). The tank's inner walls are at x = +-0.28, z = +-0.185; the palm stays within x, z = +-0.16, +-0.07.
The output is deterministic (fixed numbers, no randomness); the soak repeats the cycle.

Usage: python3 scripts/make_aggressive_hand.py [output.csv]   (python3 standard library only)
"""

import math
import os
import sys

SPEED = 2.5  # m/s, the mouse hand's maximum
GESTURE_TIME = 0.25  # s for a full change of grip or point
SURFACE = 0.15  # water surface of the hand tank [m]
DIP = 0.20  # palm height of a sweep [m]
ABOVE = 0.40  # palm height out of the water [m]
REACH = 0.16  # palm centre to the fingertips of the adult hand, a little more [m]


def yaw(angle):
    """quaternion (w, x, y, z) of a turn by `angle` about +y: the palm (+x at identity) faces (cos, 0, -sin)"""
    return (math.cos(angle / 2), 0.0, math.sin(angle / 2), 0.0)


FACE_PX = yaw(0.0)
FACE_NX = yaw(math.pi)
FACE_PZ = yaw(-math.pi / 2)
FACE_NZ = yaw(math.pi / 2)


class Track:
    def __init__(self):
        self.keys = []  # (t, (x, y, z), q, grip, point)

    def start(self, p, q, grip=0.0, point=0.0):
        self.keys.append((0.0, p, q, grip, point))

    def last(self):
        return self.keys[-1]

    def move(self, p, q=None, grip=None, point=None, speed=SPEED):
        """to p at `speed`; gesture changes take at least GESTURE_TIME per unit"""
        t0, p0, q0, g0, n0 = self.last()
        q = q0 if q is None else q
        grip = g0 if grip is None else grip
        point = n0 if point is None else point
        dt = math.dist(p0, p) / speed
        # a turn moves the fingertips (REACH from the palm centre) at most at `speed` too
        dot = min(1.0, abs(sum(a * b for a, b in zip(q0, q))))
        dt = max(dt, 2 * math.acos(dot) * REACH / speed)
        dt = max(dt, abs(grip - g0) * GESTURE_TIME, abs(point - n0) * GESTURE_TIME, 0.02)
        self.keys.append((t0 + dt, p, q, grip, point))

    def hold(self, seconds):
        t0, p0, q0, g0, n0 = self.last()
        self.keys.append((t0 + seconds, p0, q0, g0, n0))


def cycle():
    tr = Track()
    tr.start((-0.16, ABOVE, 0.0), FACE_PX)
    # 1. sweeps along x at full speed, turning to face the motion at each end (turns out of the water)
    tr.move((-0.16, DIP, 0.0))
    for _ in range(3):
        tr.move((0.16, DIP, 0.0))
        # turn in place with the fingers in the water, in two quarter turns (slerp takes the short way)
        tr.move((0.16, DIP, 0.0), q=FACE_PZ)
        tr.move((0.16, DIP, 0.0), q=FACE_NX)
        tr.move((-0.16, DIP, 0.0))
        tr.move((-0.16, DIP, 0.0), q=FACE_NZ)
        tr.move((-0.16, DIP, 0.0), q=FACE_PX)
    # 2. sweeps along z
    tr.move((0.0, ABOVE, -0.07))
    tr.move((0.0, ABOVE, -0.07), q=FACE_PZ)
    tr.hold(0.1)
    tr.move((0.0, DIP, -0.07))
    for _ in range(2):
        tr.move((0.0, DIP, 0.07))
        tr.move((0.0, DIP, 0.07), q=FACE_NX)
        tr.move((0.0, DIP, 0.07), q=FACE_NZ)
        tr.move((0.0, DIP, -0.07))
        tr.move((0.0, DIP, -0.07), q=FACE_NX)
        tr.move((0.0, DIP, -0.07), q=FACE_PZ)
    # 3. fist slams
    tr.move((0.0, ABOVE, 0.0), q=FACE_PX)
    tr.move((0.0, ABOVE, 0.0), grip=1.0)
    for x, z in ((-0.1, 0.04), (0.08, -0.05), (0.0, 0.0)):
        tr.move((x, SURFACE + 0.16, z))
        tr.move((x, 0.12, z))  # the curled fingers a few centimetres above the floor
        tr.hold(0.05)
        tr.move((x, SURFACE + 0.16, z))
    # 4. lift out and plunge, flat
    tr.move((0.05, ABOVE, 0.0), grip=0.0)
    tr.hold(0.3)
    tr.move((0.05, 0.155, 0.0))  # palm 15.5 cm up: the fingertips 4 cm above the floor
    tr.hold(0.3)
    tr.move((0.05, ABOVE, 0.0))
    tr.hold(0.2)
    # 5. point and stir two fast circles
    tr.move((0.08, DIP + 0.01, 0.0), grip=1.0, point=1.0)
    for k in range(1, 2 * 16 + 1):
        a = 2 * math.pi * k / 16
        tr.move((0.08 * math.cos(a), DIP + 0.01, 0.08 * math.sin(a)))
    tr.move((0.08, ABOVE, 0.0), grip=0.0, point=0.0)
    tr.move((-0.16, ABOVE, 0.0))
    return tr


def check(tr):
    for (t0, p0, _, g0, n0), (t1, p1, _, g1, n1) in zip(tr.keys, tr.keys[1:]):
        assert t1 > t0
        assert math.dist(p0, p1) / (t1 - t0) <= SPEED + 1e-9, (t0, t1)
        assert abs(g1 - g0) / (t1 - t0) <= 1 / GESTURE_TIME + 1e-9
        assert abs(n1 - n0) / (t1 - t0) <= 1 / GESTURE_TIME + 1e-9
        assert abs(p1[0]) <= 0.16 + 1e-9 and abs(p1[2]) <= 0.16 + 1e-9


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "assets", "hands",
                                                              "aggressive.csv")
    tr = cycle()
    check(tr)
    with open(out, "w", encoding="ascii") as f:
        f.write("time,px,py,pz,qw,qx,qy,qz,grip,point\n")
        for t, p, q, g, n in tr.keys:
            vals = [t, *p, *q, g, n]
            f.write(",".join(f"{v:.6g}" for v in vals) + "\n")
    print(f"{out}: {len(tr.keys)} keys, {tr.keys[-1][0]:.3f} s")


if __name__ == "__main__":
    main()
