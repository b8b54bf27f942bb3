#!/usr/bin/env python3
"""Generates scenes/urban_loop.yaml and scenes/meshes/urban_loop_ground.ply around a KITTI odometry trajectory.

Input: a KITTI ground-truth poses file (12 numbers a line: the 3x4 matrix T_cam0start_cam0(i), row major), e.g.
$ROTOLIDAR_DATA/kitti_poses/07.txt (the 1101-frame loop, ~694 m). The poses file itself is never committed.

Frame: the scene's world frame is the one KittiPath uses: base (x forward, y left, z up) at the first pose, i.e.
p_world = (z_cam, -x_cam, -y_cam) of each cam0 position. KITTI's cam0 rides ~1.65 m above the road, so the
ground under the path is built at z_path - 1.65 m (a height field following the trajectory's own altitude).

What is built (deterministic for a given poses file and --seed; Python's random.Random):
  - ground: a height field on a 5 m grid (PLY mesh, loaded with PCL), inverse-distance interpolated from the path
  - road slabs (10 m wide, textured) and 15 cm curbs along the path (curbs left out where streets meet)
  - buildings on both sides (boxes 6-22 m tall, set back behind a sidewalk), about half with a ground-floor
    canopy and an entrance door (annotated), some with a penthouse: real 3D structure, not clean walls
  - street trees (mesh), street lights (annotated columns), parked cars (mesh), traffic signs (retroreflective)
  - moving cars in the opposite lane and pedestrians on the sidewalks (their paths carry the ground height)
  - the default car path: the trajectory resampled every 5 m.

Usage (from the repository root):
  python3 scenes/generators/make_urban_loop.py $ROTOLIDAR_DATA/kitti_poses/07.txt
Other KITTI sequences (the KITTI twin, docs/kitti.md; large scenes stay out of the repository): write the scene
into a folder of its own, which gets the YAML, meshes/<name>_ground.ply and copies of the shared meshes it uses:
  python3 scenes/generators/make_urban_loop.py $ROTOLIDAR_DATA/kitti_poses/00.txt --name kitti_00 --out-dir DIR
"""
import argparse
import bisect
import math
import os
import random
import shutil

CAM_HEIGHT_M = 1.65
ROAD_HALF_M = 5.0      # road half width (two lanes)
SIDEWALK_M = 3.0       # from the curb to the building line
HERE = os.path.dirname(os.path.abspath(__file__))
SCENES = os.path.join(HERE, "..")


def load_path(poses_file):
    pts = []
    with open(poses_file) as f:
        for line in f:
            v = [float(x) for x in line.split()]
            if len(v) == 12:
                pts.append((v[11], -v[3], -v[7]))  # (z_cam, -x_cam, -y_cam)
    return pts


def resample(pts, step):
    """Points every `step` metres of horizontal arc length, with the unit heading there."""
    arc = [0.0]
    for a, b in zip(pts, pts[1:]):
        arc.append(arc[-1] + math.hypot(b[0] - a[0], b[1] - a[1]))
    out, s = [], 0.0
    while s <= arc[-1]:
        i = max(1, bisect.bisect_left(arc, s))
        i = min(i, len(pts) - 1)
        a, b = pts[i - 1], pts[i]
        seg = max(arc[i] - arc[i - 1], 1e-9)
        f = min(max((s - arc[i - 1]) / seg, 0.0), 1.0)
        p = tuple(a[k] + f * (b[k] - a[k]) for k in range(3))
        h = (b[0] - a[0], b[1] - a[1])
        n = math.hypot(*h) or 1.0
        out.append((p, (h[0] / n, h[1] / n), s))
        s += step
    return out


class Ground:
    """Inverse-distance-weighted ground height from the path (z_path - cam height)."""

    def __init__(self, samples):
        self.samples = [(p[0], p[1], p[2] - CAM_HEIGHT_M) for p, _, _ in samples]

    def z(self, x, y):
        num = den = 0.0
        for sx, sy, sz in self.samples:
            w = 1.0 / ((sx - x) ** 2 + (sy - y) ** 2 + 100.0) ** 2
            num += w * sz
            den += w
        return num / den


def dist_to_path(x, y, path_pts):
    return min(math.hypot(x - p[0], y - p[1]) for p in path_pts)


def rect_corners(cx, cy, yaw, half_l, half_w):
    c, s = math.cos(yaw), math.sin(yaw)
    return [(cx + c * a - s * b, cy + s * a + c * b) for a, b in
            ((half_l, half_w), (-half_l, half_w), (-half_l, -half_w), (half_l, -half_w))]


def point_rect_dist(x, y, cx, cy, yaw, half_l, half_w):
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = x - cx, y - cy
    a, b = c * dx + s * dy, -s * dx + c * dy
    ea, eb = max(abs(a) - half_l, 0.0), max(abs(b) - half_w, 0.0)
    return math.hypot(ea, eb)


def rects_overlap(r1, r2, gap):
    """Separating-axis test of two oriented rectangles (cx, cy, yaw, half_l, half_w) grown by gap/2 each."""
    rs = [(r[0], r[1], r[2], r[3] + gap / 2, r[4] + gap / 2) for r in (r1, r2)]
    for r in rs:
        for ax in ((math.cos(r[2]), math.sin(r[2])), (-math.sin(r[2]), math.cos(r[2]))):
            proj = []
            for q in rs:
                cs = rect_corners(*q)
                vals = [ax[0] * px + ax[1] * py for px, py in cs]
                proj.append((min(vals), max(vals)))
            if proj[0][1] < proj[1][0] or proj[1][1] < proj[0][0]:
                return False
    return True


def fmt(v):
    return "[" + ", ".join("%.3f" % x for x in v) + "]"


class Builder:
    def __init__(self, samples, rng):
        self.samples = samples
        self.path_pts = [p for p, _, _ in samples]
        self.ground = Ground(samples)
        self.rng = rng
        self.prims, self.elements, self.dynamic = [], [], []
        self.buildings = []   # oriented rectangles
        self.obstacles = []   # (x, y, radius) of trees, poles, parked cars

    def near_other_street(self, x, y, s_here, radius):
        """True when a path point farther than 12 m of arc from s_here lies within `radius` of (x, y): where
        streets meet or the path turns, so curbs and parked cars stay off the road the path takes."""
        return any(abs(s - s_here) > 12.0 and math.hypot(x - p[0], y - p[1]) < radius for p, _, s in self.samples)

    def road(self):
        for i in range(0, len(self.samples) - 1, 5):  # samples every 2 m: a slab every 10 m
            (p, h, s) = self.samples[i]
            j = min(i + 5, len(self.samples) - 1)
            q = self.samples[j][0]
            mx, my = (p[0] + q[0]) / 2, (p[1] + q[1]) / 2
            length = math.hypot(q[0] - p[0], q[1] - p[1]) + 0.6
            yaw = math.degrees(math.atan2(q[1] - p[1], q[0] - p[0]))
            z0, z1 = self.ground.z(p[0], p[1]), self.ground.z(q[0], q[1])
            pitch = -math.degrees(math.atan2(z1 - z0, length))
            zc = (z0 + z1) / 2 + 0.05 - 0.1   # slab 0.2 thick, its top 5 cm above the ground field
            self.prims.append("  - {type: box, name: road_%d, center: %s, size: [%.2f, %.1f, 0.2], rpy_deg: [0, %.3f, %.2f],"
                              " material: road}" % (i, fmt((mx, my, zc)), length, 2 * ROAD_HALF_M, pitch, yaw))
            for side in (1, -1):
                cx, cy = mx - side * h[1] * (ROAD_HALF_M + 0.15), my + side * h[0] * (ROAD_HALF_M + 0.15)
                if self.near_other_street(cx, cy, s, ROAD_HALF_M + 3.0):
                    continue
                self.prims.append("  - {type: box, name: curb_%d_%s, center: %s, size: [%.2f, 0.3, 0.3],"
                                  " rpy_deg: [0, %.3f, %.2f], material: curb}"
                                  % (i, "l" if side > 0 else "r", fmt((cx, cy, zc + 0.1)), length, pitch, yaw))

    def building(self, idx, p, h, side, s):
        rng = self.rng
        half_l, half_w = rng.uniform(4.5, 8.0), rng.uniform(4.0, 7.0)
        height = rng.uniform(6.0, 22.0)
        setback = ROAD_HALF_M + SIDEWALK_M + half_w + rng.uniform(0.0, 1.5)
        nx, ny = -side * h[1], side * h[0]  # unit normal towards this side
        cx, cy = p[0] + nx * setback, p[1] + ny * setback
        yaw = math.atan2(h[1], h[0])
        rect = (cx, cy, yaw, half_l, half_w)
        if min(point_rect_dist(q[0], q[1], *rect) for q in self.path_pts) < ROAD_HALF_M + SIDEWALK_M - 0.01:
            return
        if any(rects_overlap(rect, r, 1.5) for r in self.buildings):
            return
        self.buildings.append(rect)
        base = min(self.ground.z(x, y) for x, y in rect_corners(*rect)) - 0.5
        material = rng.choice(["facade", "facade_glass", "bricks", "facade"])
        self.prims.append("  - {type: box, name: building_%d, center: %s, size: [%.2f, %.2f, %.2f], yaw_deg: %.2f,"
                          " material: %s}" % (idx, fmt((cx, cy, base + height / 2)), 2 * half_l, 2 * half_w, height,
                                              math.degrees(yaw), material))
        front_x, front_y = cx - nx * half_w, cy - ny * half_w  # facade centre on the street side
        g = self.ground.z(front_x, front_y)
        if rng.random() < 0.55:   # canopy over an entrance door
            self.prims.append("  - {type: box, name: canopy_%d, center: %s, size: [%.2f, 1.6, 0.2], yaw_deg: %.2f,"
                              " material: concrete}" % (idx, fmt((front_x - nx * 0.79, front_y - ny * 0.79, g + 3.3)),
                                                        1.2 * half_l, math.degrees(yaw)))
            # door leaf 1 cm in front of the facade, facing the street: quad normal = -n
            roll = 90.0 if side > 0 else -90.0
            self.prims.append("  - {type: quad, name: door_%d, center: %s, size: [1.4, 2.3], rpy_deg: [%.1f, 0, %.2f],"
                              " material: door}" % (idx, fmt((front_x - nx * 0.01, front_y - ny * 0.01, g + 1.15)),
                                                    roll, math.degrees(yaw)))
            self.elements.append("  - {name: door_%d, type: door, center: %s, width: 1.4, height: 2.3, depth: 0.0,"
                                 " yaw_deg: %.2f}" % (idx, fmt((front_x, front_y, g + 1.15)),
                                                      math.degrees(math.atan2(ny, nx))))
        if rng.random() < 0.4:    # penthouse
            self.prims.append("  - {type: box, name: penthouse_%d, center: %s, size: [%.2f, %.2f, 3.0], yaw_deg: %.2f,"
                              " material: concrete, hide_in_top_view: false}"
                              % (idx, fmt((cx + nx * 1.0, cy + ny * 1.0, base + height + 1.49)), half_l, half_w,
                                 math.degrees(yaw)))

    def free_spot(self, x, y, radius):
        if any(point_rect_dist(x, y, *r) < radius for r in self.buildings):
            return False
        return all(math.hypot(x - ox, y - oy) > radius + orad for ox, oy, orad in self.obstacles)

    def street_furniture(self):
        rng = self.rng
        for k, (p, h, s) in enumerate(self.samples):
            if k % 9 == 0:   # trees every ~18 m, alternating sides
                side = 1 if (k // 9) % 2 else -1
                off = ROAD_HALF_M + 1.6
                x, y = p[0] - side * h[1] * off, p[1] + side * h[0] * off
                if dist_to_path(x, y, self.path_pts) > off - 0.05 and self.free_spot(x, y, 2.0):
                    self.obstacles.append((x, y, 1.9))
                    self.prims.append("  - {type: mesh, name: tree_%d, file: meshes/tree.ply, center: %s, yaw_deg: %d,"
                                      " scale: %.2f, material: foliage}"
                                      % (k, fmt((x, y, self.ground.z(x, y) - 0.05)), rng.randrange(360),
                                         rng.uniform(0.85, 1.15)))
            if k % 17 == 4:  # street lights every ~34 m
                side = 1 if (k // 17) % 2 else -1
                off = ROAD_HALF_M + 0.6
                x, y = p[0] - side * h[1] * off, p[1] + side * h[0] * off
                if dist_to_path(x, y, self.path_pts) > off - 0.05 and self.free_spot(x, y, 1.0):
                    self.obstacles.append((x, y, 0.3))
                    g = self.ground.z(x, y)
                    self.prims.append("  - {type: cylinder, name: light_%d, center: %s, radius: 0.1, height: 7.0,"
                                      " segments: 12, material: metal}" % (k, fmt((x, y, g + 3.49))))
                    self.elements.append("  - {name: light_%d, type: column, center: %s, width: 0.2, height: 7.0,"
                                         " depth: 0.2, primitive: light_%d}" % (k, fmt((x, y, g + 3.49)), k))
            if k % 23 == 11:  # traffic signs (retroreflective) on short posts
                side = -1
                off = ROAD_HALF_M + 0.9
                x, y = p[0] - side * h[1] * off, p[1] + side * h[0] * off
                if dist_to_path(x, y, self.path_pts) > off - 0.05 and self.free_spot(x, y, 0.6):
                    self.obstacles.append((x, y, 0.4))
                    g = self.ground.z(x, y)
                    yaw = math.degrees(math.atan2(h[1], h[0]))
                    self.prims.append("  - {type: cylinder, name: sign_post_%d, center: %s, radius: 0.04, height: 2.6,"
                                      " segments: 8, material: metal}" % (k, fmt((x, y, g + 1.29))))
                    self.prims.append("  - {type: quad, name: sign_%d, center: %s, size: [0.7, 0.7],"
                                      " rpy_deg: [0, -90, %.2f], material: sign}"
                                      % (k, fmt((x - h[0] * 0.06, y - h[1] * 0.06, g + 2.3)), yaw))
            if k % 7 == 3 and rng.random() < 0.6:  # parked cars in the parking lane
                side = 1 if rng.random() < 0.5 else -1
                off = ROAD_HALF_M - 0.95
                x, y = p[0] - side * h[1] * off, p[1] + side * h[0] * off
                if dist_to_path(x, y, self.path_pts) > off - 0.05 and self.free_spot(x, y, 2.4) and \
                        not self.near_other_street(x, y, s, ROAD_HALF_M + 2.5):
                    self.obstacles.append((x, y, 2.4))
                    yaw = math.degrees(math.atan2(h[1], h[0])) + rng.uniform(-3, 3)
                    self.prims.append("  - {type: mesh, name: parked_%d, file: meshes/sedan.obj, center: %s,"
                                      " yaw_deg: %.2f, material: %s}"
                                      % (k, fmt((x, y, self.ground.z(x, y) + 0.02)), yaw,
                                         rng.choice(["car_red", "car_white", "car_grey", "car_blue"])))

    def traffic(self):
        lane = [s for k, s in enumerate(self.samples) if k % 5 == 0]
        pts = []
        for p, h, _ in lane:   # the opposite lane: 2 m to the right of the trajectory
            x, y = p[0] + h[1] * 2.0, p[1] - h[0] * 2.0
            pts.append((x, y, self.ground.z(x, y)))
        path = ", ".join(fmt(q) for q in pts)
        for i, (speed, offset, mat) in enumerate(((7.0, 0.0, "car_white"), (8.0, 230.0, "car_red"),
                                                  (6.5, 460.0, "car_blue"))):
            self.dynamic.append("  - {name: traffic_%d, kind: car, material: %s, speed: %.1f, start_offset: %.1f,\n"
                                "     path: [%s]}" % (i, mat, speed, offset, path))
        for i, k in enumerate((30, 120, 210, 300)):  # pedestrians walking 30 m of sidewalk back and forth
            if k + 15 >= len(self.samples):
                continue
            walk = []
            for p, h, _ in (self.samples[k], self.samples[k + 15]):
                x, y = p[0] - h[1] * (ROAD_HALF_M + 1.2), p[1] + h[0] * (ROAD_HALF_M + 1.2)
                walk.append((x, y, self.ground.z(x, y)))
            self.dynamic.append("  - {name: pedestrian_%d, kind: person, material: clothes, speed: 1.3, loop: false,"
                                " path: [%s]}" % (i, ", ".join(fmt(q) for q in walk)))


def write_ground(builder, bounds, path):
    (x0, y0), (x1, y1) = bounds
    step = 5.0
    nx, ny = int(math.ceil((x1 - x0) / step)) + 1, int(math.ceil((y1 - y0) / step)) + 1
    verts = [(x0 + i * step, y0 + j * step, builder.ground.z(x0 + i * step, y0 + j * step))
             for j in range(ny) for i in range(nx)]
    faces = []
    for j in range(ny - 1):
        for i in range(nx - 1):
            a, b, c, d = j * nx + i, j * nx + i + 1, (j + 1) * nx + i + 1, (j + 1) * nx + i
            faces += [(a, b, c), (a, c, d)]   # counter-clockwise seen from above
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\ncomment urban_loop ground height field (make_urban_loop.py)\n"
                "element vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
                "element face %d\nproperty list uchar int vertex_indices\nend_header\n" % (len(verts), len(faces)))
        for v in verts:
            f.write("%.2f %.2f %.3f\n" % v)
        for a, b, c in faces:
            f.write("3 %d %d %d\n" % (a, b, c))
    return min(v[2] for v in verts), max(v[2] for v in verts)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("poses", help="KITTI poses file (e.g. kitti_poses/07.txt)")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--name", default="urban_loop")
    ap.add_argument("--out-dir", default=SCENES, help="folder for <name>.yaml and meshes/ (default: scenes/)")
    args = ap.parse_args()
    out_dir = args.out_dir
    os.makedirs(os.path.join(out_dir, "meshes"), exist_ok=True)
    if os.path.abspath(out_dir) != os.path.abspath(SCENES):
        for mesh in ("tree.ply", "sedan.obj"):  # the shared meshes the scene refers to (relative to the YAML)
            shutil.copyfile(os.path.join(SCENES, "meshes", mesh), os.path.join(out_dir, "meshes", mesh))
    rng = random.Random(args.seed)
    samples = resample(load_path(args.poses), 2.0)
    b = Builder(samples, rng)
    b.road()
    for k in range(0, len(samples), 6):
        p, h, s = samples[k]
        for side in (1, -1):
            if rng.random() < 0.85:
                b.building(len(b.buildings) * 2 + (side > 0), p, h, side, s)
    b.street_furniture()
    b.traffic()
    xs, ys = [p[0] for p, _, _ in samples], [p[1] for p, _, _ in samples]
    margin = 40.0
    ground_box = ((min(xs) - margin, min(ys) - margin), (max(xs) + margin, max(ys) + margin))
    zmin, zmax = write_ground(b, ground_box, os.path.join(out_dir, "meshes", args.name + "_ground.ply"))
    car_path = [samples[k] for k in range(0, len(samples), 3)]  # every 6 m
    length = samples[-1][2]
    with open(os.path.join(out_dir, args.name + ".yaml"), "w") as f:
        f.write("# GENERATED by scenes/generators/make_urban_loop.py from %s (seed %d): do not edit by hand.\n"
                % (os.path.basename(args.poses), args.seed))
        f.write("# Streets with buildings along a KITTI trajectory (%.0f m, a loop: the end revisits the start), in "
                "KittiPath's frame:\n# base at the first pose (x forward, y left, z up); the ground is 1.65 m below "
                "the cam0 path (a height field).\n# Default car path: the trajectory every 6 m (2-D; the ground "
                "height comes from the scene).\n" % length)
        f.write("format_version: 1\nname: %s\ndescription: city streets along KITTI %s with revisits for loop "
                "closure\nclosed: false\n" % (args.name, os.path.splitext(os.path.basename(args.poses))[0]))
        f.write("bounds: {min: %s, max: %s}\n\n" % (fmt((min(xs) - 15, min(ys) - 15, zmin - 1.0)),
                                                   fmt((max(xs) + 15, max(ys) + 15, zmax + 30.0))))
        f.write(MATERIALS)
        f.write("\nprimitives:\n  - {type: mesh, name: ground, file: meshes/%s_ground.ply, center: [0, 0, 0], "
                "material: ground}\n" % args.name)
        f.write("\n".join(b.prims) + "\n\nelements:\n" + "\n".join(b.elements) + "\n\ndynamic:\n")
        f.write("\n".join(b.dynamic) + "\n\npaths:\n  car: [")
        f.write(", ".join("[%.2f, %.2f%s]" % (p[0], p[1], ", 2.0" if i == 0 else "")
                          for i, (p, _, _) in enumerate(car_path)) + "]\n")
        f.write(LIGHTING)
        p0 = samples[0][0]
        f.write("view: {eye: %s, target: %s, fov_deg: 55}\n" % (fmt((p0[0] - 120, p0[1] - 110, p0[2] + 150)),
                                                              fmt((p0[0] + 20, p0[1] + 90, p0[2] - 10))))


MATERIALS = """materials:
  - {name: ground, albedo: 0.30, color: [0.42, 0.44, 0.40]}
  - {name: road, albedo: 0.18, texture: road}
  - {name: curb, albedo: 0.45, texture: concrete}
  - {name: facade, albedo: 0.55, texture: facade}
  - {name: facade_glass, albedo: 0.25, texture: facade_glass}
  - {name: bricks, albedo: 0.40, texture: bricks}
  - {name: concrete, albedo: 0.45, texture: concrete}
  - {name: door, albedo: 0.40, texture: door}
  - {name: metal, albedo: 0.55, texture: metal}
  - {name: foliage, albedo: 0.30, texture: foliage}
  - {name: sign, albedo: 0.90, retroreflective: true, texture: exit_sign}
  - {name: car_red, albedo: 0.30, texture: car_paint, color: [0.75, 0.15, 0.12]}
  - {name: car_blue, albedo: 0.25, texture: car_paint, color: [0.15, 0.25, 0.65]}
  - {name: car_white, albedo: 0.70, texture: car_paint}
  - {name: car_grey, albedo: 0.35, texture: car_paint, color: [0.45, 0.46, 0.48]}
  - {name: clothes, albedo: 0.25, texture: cloth}
"""

LIGHTING = """
lighting:
  ambient: 0.40
  headlight: 0.25
  sky: [0.55, 0.70, 0.92]
  lights:
    - {directional: true, direction: [-0.3, 0.4, -0.85], intensity: 0.55}

"""

if __name__ == "__main__":
    main()
