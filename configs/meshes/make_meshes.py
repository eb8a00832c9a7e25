#!/usr/bin/env python3
"""Writes the meshes of configs/tank_riser.yaml (ASCII STL, metres, z up). Run from this folder:
python3 make_meshes.py
  pump.stl  a mixer pump hanging in the tank: a 12-sided column 0.25 m across and 5 m tall over a
            12-sided head 0.7 m across and 1 m tall, its origin at the head's top centre;
  dome.stl  the tank's concrete dome around the riser: a 24-sided ring 0.3 m thick from the riser's
            bore (0.3 m radius) out to 3 m, its origin at the centre of its underside."""
import math

def ring(r_in, r_out, z0, z1, n=48):
    """A flat ring (annulus) between z0 and z1, its inner and outer walls and both faces."""
    tris = []
    pt = lambda r, k: (r * math.cos(2 * math.pi * k / n), r * math.sin(2 * math.pi * k / n))
    for k in range(n):
        (a0, b0), (a1, b1) = pt(r_in, k), pt(r_in, k + 1)
        (c0, d0), (c1, d1) = pt(r_out, k), pt(r_out, k + 1)
        tris += [((c0, d0, z0), (c1, d1, z0), (c1, d1, z1)), ((c0, d0, z0), (c1, d1, z1), (c0, d0, z1))]  # outer wall
        tris += [((a1, b1, z0), (a0, b0, z0), (a0, b0, z1)), ((a1, b1, z0), (a0, b0, z1), (a1, b1, z1))]  # bore wall
        tris += [((a0, b0, z0), (c1, d1, z0), (c0, d0, z0)), ((a0, b0, z0), (a1, b1, z0), (c1, d1, z0))]  # underside
        tris += [((a0, b0, z1), (c0, d0, z1), (c1, d1, z1)), ((a0, b0, z1), (c1, d1, z1), (a1, b1, z1))]  # top
    return tris

def prism(r, z0, z1, n=12):
    tris = []
    ring = [(r * math.cos(2 * math.pi * k / n), r * math.sin(2 * math.pi * k / n)) for k in range(n)]
    for k in range(n):
        (x0, y0), (x1, y1) = ring[k], ring[(k + 1) % n]
        tris += [((x0, y0, z0), (x1, y1, z0), (x1, y1, z1)), ((x0, y0, z0), (x1, y1, z1), (x0, y0, z1))]
        tris += [((0, 0, z0), (x1, y1, z0), (x0, y0, z0)), ((0, 0, z1), (x0, y0, z1), (x1, y1, z1))]
    return tris

def normal(a, b, c):
    u = [b[i] - a[i] for i in range(3)]
    v = [c[i] - a[i] for i in range(3)]
    n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    l = math.sqrt(sum(x * x for x in n)) or 1.0
    return [x / l for x in n]

def write(path, name, tris):
    with open(path, "w") as f:
        f.write("solid %s\n" % name)
        for t in tris:
            f.write("  facet normal %.6f %.6f %.6f\n    outer loop\n" % tuple(normal(*t)))
            for p in t:
                f.write("      vertex %.6f %.6f %.6f\n" % p)
            f.write("    endloop\n  endfacet\n")
        f.write("endsolid %s\n" % name)

write("pump.stl", "pump", prism(0.125, 0.0, 5.0) + prism(0.35, -1.0, 0.0))
# The ring's bore a little wider than the riser's (its flats at the riser's radius, 0.3 / cos(pi / 24)).
write("dome.stl", "dome", ring(0.3 / math.cos(math.pi / 24), 3.0, 0.0, 0.3, n=24))
