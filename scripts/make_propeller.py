#!/usr/bin/env python3
"""Writes assets/meshes/propeller.obj: a three-blade propeller for the propeller scene.

Local frame: spin axis = +z, centred at the origin, blade tip radius 0.5 (unit diameter). The mesh is a union of
four closed, consistently outward-oriented (counter-clockwise seen from outside) components: a hub cylinder
(radius 0.08, length 0.16 along z) and three blades whose roots start inside the hub. The components overlap; the
simulator treats them as a union (signed distance = minimum over components).

Each blade is a swept elliptical section (chord ~0.14, thickness ~0.03) pitched ~25 degrees about its radial axis,
twisted from 33 degrees at the root to 19 degrees at the tip. Sections are wrapped onto cylinders r = const, so the
blade is a true helical slab and the tip lies exactly at radius 0.5.

Usage: python3 scripts/make_propeller.py [output.obj]   (python3 standard library only; output is deterministic)
"""

import math
import os
import sys
from collections import Counter

TIP_RADIUS = 0.5
HUB_RADIUS = 0.08
HUB_HALF_LENGTH = 0.08
HUB_SEGMENTS = 40
BLADES = 3
ROOT_RADIUS = 0.05  # inside the hub, so each blade fuses with it
STATIONS = 16  # radial sections per blade
PROFILE_POINTS = 16  # points around each section


def chord(r):
    """Chord [m]: 0.10 at the root, widest (0.14) at 60 % of the span, 0.06 at the tip."""
    s = (r - ROOT_RADIUS) / (TIP_RADIUS - ROOT_RADIUS)
    if s < 0.6:
        return 0.10 + (0.14 - 0.10) * math.sin(0.5 * math.pi * s / 0.6)
    return 0.14 - (0.14 - 0.06) * ((s - 0.6) / 0.4) ** 2


def thickness(r):
    """Thickness [m]: 0.03 at the root, 0.02 at the tip."""
    s = (r - ROOT_RADIUS) / (TIP_RADIUS - ROOT_RADIUS)
    return 0.03 - 0.01 * s


def pitch(r):
    """Pitch angle of the chord to the rotation plane [rad]: 33 degrees at the root, 19 at the tip (~25 mid-span)."""
    s = (r - ROOT_RADIUS) / (TIP_RADIUS - ROOT_RADIUS)
    return math.radians(33.0 - 14.0 * s)


class Mesh:
    def __init__(self):
        self.vertices = []
        self.triangles = []

    def vertex(self, p):
        self.vertices.append(p)
        return len(self.vertices) - 1

    def begin_component(self):
        return len(self.triangles)

    def orient_component(self, first_triangle):
        """Flips the component's triangles if its signed volume is negative (inward normals)."""
        tris = self.triangles[first_triangle:]
        if signed_volume(self.vertices, tris) < 0.0:
            self.triangles[first_triangle:] = [(a, c, b) for (a, b, c) in tris]


def signed_volume(vertices, triangles):
    vol = 0.0
    for a, b, c in triangles:
        ax, ay, az = vertices[a]
        bx, by, bz = vertices[b]
        cx, cy, cz = vertices[c]
        vol += ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)
    return vol / 6.0


def add_hub(mesh):
    first = mesh.begin_component()
    n = HUB_SEGMENTS
    bottom = [mesh.vertex((HUB_RADIUS * math.cos(2 * math.pi * i / n), HUB_RADIUS * math.sin(2 * math.pi * i / n),
                           -HUB_HALF_LENGTH)) for i in range(n)]
    top = [mesh.vertex((HUB_RADIUS * math.cos(2 * math.pi * i / n), HUB_RADIUS * math.sin(2 * math.pi * i / n),
                        HUB_HALF_LENGTH)) for i in range(n)]
    cb = mesh.vertex((0.0, 0.0, -HUB_HALF_LENGTH))
    ct = mesh.vertex((0.0, 0.0, HUB_HALF_LENGTH))
    for i in range(n):
        j = (i + 1) % n
        # side (counter-clockwise seen from outside: bottom i -> bottom j -> top j)
        mesh.triangles.append((bottom[i], bottom[j], top[j]))
        mesh.triangles.append((bottom[i], top[j], top[i]))
        mesh.triangles.append((ct, top[i], top[j]))  # top cap faces +z
        mesh.triangles.append((cb, bottom[j], bottom[i]))  # bottom cap faces -z
    mesh.orient_component(first)


def blade_point(r, u, v, azimuth):
    """Point of the section at radius r: chord coordinate u, thickness coordinate v, pitched and wrapped onto the
    cylinder of radius r around the blade's azimuth."""
    theta = pitch(r)
    tangential = u * math.cos(theta) - v * math.sin(theta)
    z = u * math.sin(theta) + v * math.cos(theta)
    phi = azimuth + tangential / r
    return (r * math.cos(phi), r * math.sin(phi), z)


def add_blade(mesh, azimuth):
    first = mesh.begin_component()
    m = PROFILE_POINTS
    rings = []
    centres = []
    for k in range(STATIONS):
        # stations denser towards the tip, where the chord changes fastest
        s = k / (STATIONS - 1)
        r = ROOT_RADIUS + (TIP_RADIUS - ROOT_RADIUS) * math.sin(0.5 * math.pi * s)
        if k == STATIONS - 1:
            r = TIP_RADIUS
        c, t = chord(r), thickness(r)
        ring = []
        for i in range(m):
            a = 2 * math.pi * i / m
            ring.append(mesh.vertex(blade_point(r, 0.5 * c * math.cos(a), 0.5 * t * math.sin(a), azimuth)))
        rings.append(ring)
        centres.append(blade_point(r, 0.0, 0.0, azimuth))
    for k in range(STATIONS - 1):
        lo, hi = rings[k], rings[k + 1]
        for i in range(m):
            j = (i + 1) % m
            mesh.triangles.append((lo[i], lo[j], hi[j]))
            mesh.triangles.append((lo[i], hi[j], hi[i]))
    root = mesh.vertex(centres[0])
    tip = mesh.vertex(centres[-1])
    for i in range(m):
        j = (i + 1) % m
        mesh.triangles.append((root, rings[0][j], rings[0][i]))
        mesh.triangles.append((tip, rings[-1][i], rings[-1][j]))
    mesh.orient_component(first)


def check(mesh):
    """Every directed edge once and its reverse once: closed and consistently oriented."""
    directed = Counter()
    for a, b, c in mesh.triangles:
        for e in ((a, b), (b, c), (c, a)):
            directed[e] += 1
    for (a, b), count in directed.items():
        if count != 1 or directed.get((b, a), 0) != 1:
            raise SystemExit(f"mesh is not closed and consistently oriented at edge {a}-{b}")
    if signed_volume(mesh.vertices, mesh.triangles) <= 0.0:
        raise SystemExit("mesh has inward orientation")


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(root, "assets", "meshes", "propeller.obj")
    mesh = Mesh()
    add_hub(mesh)
    for b in range(BLADES):
        add_blade(mesh, 2 * math.pi * b / BLADES)
    check(mesh)
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "w", encoding="ascii", newline="\n") as f:
        f.write("# Three-blade propeller, generated by scripts/make_propeller.py; do not edit.\n")
        f.write("# Local frame: spin axis +z, centred at the origin, tip radius 0.5 m. Union of 4 closed components\n")
        f.write("# (hub + 3 blades, overlapping), counter-clockwise seen from outside.\n")
        f.write(f"# {len(mesh.vertices)} vertices, {len(mesh.triangles)} triangles\n")
        for x, y, z in mesh.vertices:
            f.write(f"v {x:.9f} {y:.9f} {z:.9f}\n")
        for a, b, c in mesh.triangles:
            f.write(f"f {a + 1} {b + 1} {c + 1}\n")
    print(f"wrote {out}: {len(mesh.vertices)} vertices, {len(mesh.triangles)} triangles")


if __name__ == "__main__":
    main()
