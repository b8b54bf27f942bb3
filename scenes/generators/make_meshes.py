#!/usr/bin/env python3
"""Writes the small mesh assets of scenes/meshes/ (stdlib only, deterministic).

  sedan.obj  a parked car: lower body and cabin (extruded side profiles) and four wheels, closed, ~4.5 x 1.8 x 1.45 m
  tree.ply   a street tree: octagonal trunk and a faceted ellipsoid crown, closed, ~3.6 m wide, 6.2 m tall
  leaf_crown.ply  a porous crown: 800 leaves (thin closed tetrahedra, 0.2 m triangles 1 cm thick) scattered in
             tree.ply's crown ellipsoid (radii 1.8, 1.7, 2.1 m about (0, 0, 4.1)); no trunk. A third of horizontal
             rays through its middle (|y| < 0.8 m, |z - 4.1| < 1 m) pass between the leaves (ray cast, 300 rays).

Frames: x forward (car), z up, origin on the ground at the object's centre. Triangles wind counter-clockwise seen
from outside. Run from the repository root:  python3 scenes/generators/make_meshes.py
"""
import math
import os

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "meshes")


class Mesh:
    def __init__(self):
        self.v, self.f = [], []

    def vertex(self, p):
        self.v.append(tuple(p))
        return len(self.v) - 1

    def tri(self, a, b, c):
        self.f.append((a, b, c))


def extrude_profile(mesh, profile_xz, y0, y1):
    """A prism: the polygon (x, z), counter-clockwise seen from -y, extruded from y0 to y1 (closed)."""
    n = len(profile_xz)
    cx = sum(p[0] for p in profile_xz) / n
    cz = sum(p[1] for p in profile_xz) / n
    near = [mesh.vertex((x, y0, z)) for x, z in profile_xz]
    far = [mesh.vertex((x, y1, z)) for x, z in profile_xz]
    c_near, c_far = mesh.vertex((cx, y0, cz)), mesh.vertex((cx, y1, cz))
    for i in range(n):
        j = (i + 1) % n
        mesh.tri(c_near, near[i], near[j])     # cap facing -y (polygon ccw seen from -y)
        mesh.tri(c_far, far[j], far[i])        # cap facing +y
        mesh.tri(near[i], far[i], far[j])      # side, facing outwards
        mesh.tri(near[i], far[j], near[j])


def cylinder(mesh, center, radius, half_height, axis, segments):
    """A closed prism around `axis` ('y' or 'z') through `center`, outward winding."""
    def point(angle, h):
        a, b = radius * math.cos(angle), radius * math.sin(angle)
        if axis == "z":
            return (center[0] + a, center[1] + b, center[2] + h)
        return (center[0] + b, center[1] + h, center[2] + a)  # axis y: (x, z) = (b, a), ccw about +y
    lo = [mesh.vertex(point(2 * math.pi * k / segments, -half_height)) for k in range(segments)]
    hi = [mesh.vertex(point(2 * math.pi * k / segments, half_height)) for k in range(segments)]
    axis_vec = (0.0, 0.0, 1.0) if axis == "z" else (0.0, 1.0, 0.0)
    c_lo = mesh.vertex(tuple(c - half_height * a for c, a in zip(center, axis_vec)))
    c_hi = mesh.vertex(tuple(c + half_height * a for c, a in zip(center, axis_vec)))
    for k in range(segments):
        m = (k + 1) % segments
        mesh.tri(lo[k], lo[m], hi[m])
        mesh.tri(lo[k], hi[m], hi[k])
        mesh.tri(hi[k], hi[m], c_hi)
        mesh.tri(lo[m], lo[k], c_lo)


def ellipsoid(mesh, center, radii, rings, sectors):
    """A closed faceted ellipsoid (latitude-longitude), outward winding."""
    top = mesh.vertex((center[0], center[1], center[2] + radii[2]))
    bottom = mesh.vertex((center[0], center[1], center[2] - radii[2]))
    rows = []
    for r in range(1, rings):
        theta = math.pi * r / rings
        row = []
        for s in range(sectors):
            phi = 2 * math.pi * s / sectors + (0.5 * math.pi / sectors if r % 2 else 0.0)
            row.append(mesh.vertex((center[0] + radii[0] * math.sin(theta) * math.cos(phi),
                                    center[1] + radii[1] * math.sin(theta) * math.sin(phi),
                                    center[2] + radii[2] * math.cos(theta))))
        rows.append(row)
    for s in range(sectors):
        t = (s + 1) % sectors
        mesh.tri(top, rows[0][s], rows[0][t])
        mesh.tri(bottom, rows[-1][t], rows[-1][s])
    for r in range(len(rows) - 1):
        for s in range(sectors):
            t = (s + 1) % sectors
            a, b, c, d = rows[r][s], rows[r][t], rows[r + 1][s], rows[r + 1][t]
            mesh.tri(a, c, d)
            mesh.tri(a, d, b)


def sedan():
    m = Mesh()
    body = [(-2.25, 0.28), (2.20, 0.28), (2.30, 0.50), (2.22, 0.82), (1.00, 0.95), (-2.05, 0.97),
            (-2.30, 0.80), (-2.32, 0.45)]
    cabin = [(1.05, 0.94), (0.15, 1.42), (-1.35, 1.44), (-2.00, 0.96)]
    extrude_profile(m, body, -0.90, 0.90)  # profiles run counter-clockwise in (x, z)
    extrude_profile(m, cabin, -0.76, 0.76)
    for x in (-1.40, 1.40):
        for y in (-0.80, 0.80):
            cylinder(m, (x, y, 0.32), 0.32, 0.11, "y", 14)
    return m


def tree():
    m = Mesh()
    cylinder(m, (0.0, 0.0, 1.30), 0.16, 1.30, "z", 8)
    ellipsoid(m, (0.0, 0.0, 4.10), (1.80, 1.70, 2.10), 6, 10)
    return m


def leaf_crown(count=800, side=0.20, thickness=0.01, seed=2024):
    """Leaves uniformly in the crown ellipsoid, random orientation; a 64-bit LCG keeps it the same everywhere."""
    state = [seed]

    def uniform():  # Knuth's MMIX LCG, top 53 bits
        state[0] = (state[0] * 6364136223846793005 + 1442695040888963407) % (1 << 64)
        return (state[0] >> 11) / float(1 << 53)

    centre, radii = (0.0, 0.0, 4.1), (1.8, 1.7, 2.1)
    m = Mesh()
    for _ in range(count):
        while True:  # rejection sampling inside the ellipsoid (shrunk by one leaf)
            u = [2.0 * uniform() - 1.0 for _ in range(3)]
            if sum(x * x for x in u) <= 1.0:
                break
        c = [centre[i] + u[i] * (radii[i] - side) for i in range(3)]
        while True:  # a random unit normal
            n = [2.0 * uniform() - 1.0 for _ in range(3)]
            r = math.sqrt(sum(x * x for x in n))
            if 0.1 < r <= 1.0:
                n = [x / r for x in n]
                break
        a = [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0]  # in-plane axes e1, e2
        e1 = [a[1] * n[2] - a[2] * n[1], a[2] * n[0] - a[0] * n[2], a[0] * n[1] - a[1] * n[0]]
        l1 = math.sqrt(sum(x * x for x in e1))
        e1 = [x / l1 for x in e1]
        e2 = [n[1] * e1[2] - n[2] * e1[1], n[2] * e1[0] - n[0] * e1[2], n[0] * e1[1] - n[1] * e1[0]]
        phi = 2.0 * math.pi * uniform()
        rad = side / math.sqrt(3.0)  # circumradius of an equilateral triangle of this side
        corners = []
        for k in range(3):
            ang = phi + 2.0 * math.pi * k / 3.0
            corners.append([c[i] + rad * (math.cos(ang) * e1[i] + math.sin(ang) * e2[i]) for i in range(3)])
        apex = [c[i] + thickness * n[i] for i in range(3)]
        v0, v1, v2, v3 = (m.vertex(p) for p in corners + [apex])
        # corners go counter-clockwise about n: the base faces -n, the sides face outwards
        m.tri(v0, v2, v1)
        m.tri(v0, v1, v3)
        m.tri(v1, v2, v3)
        m.tri(v2, v0, v3)
    return m


def write_obj(mesh, path, comment):
    with open(path, "w") as f:
        f.write("# %s\n# %d vertices, %d triangles; metres, z up, ccw = outside\n" % (comment, len(mesh.v), len(mesh.f)))
        for v in mesh.v:
            f.write("v %.4f %.4f %.4f\n" % v)
        for a, b, c in mesh.f:
            f.write("f %d %d %d\n" % (a + 1, b + 1, c + 1))


def write_ply(mesh, path, comment):
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\ncomment %s\nelement vertex %d\nproperty float x\nproperty float y\n"
                "property float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n"
                % (comment, len(mesh.v), len(mesh.f)))
        for v in mesh.v:
            f.write("%.4f %.4f %.4f\n" % v)
        for a, b, c in mesh.f:
            f.write("3 %d %d %d\n" % (a, b, c))


if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    write_obj(sedan(), os.path.join(OUT, "sedan.obj"), "rotolidar sedan (scenes/generators/make_meshes.py)")
    write_ply(tree(), os.path.join(OUT, "tree.ply"), "rotolidar street tree (scenes/generators/make_meshes.py)")
    write_ply(leaf_crown(), os.path.join(OUT, "leaf_crown.ply"),
              "rotolidar porous leaf crown (scenes/generators/make_meshes.py)")
