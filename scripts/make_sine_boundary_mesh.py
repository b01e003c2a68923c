#!/usr/bin/env python3
"""Write a Gmsh MSH 4.1 ASCII triangle mesh of a strip whose lower boundary
follows y = y0 + A cos(2 pi x / wavelength) and whose top is flat at y0 + H
(the FEM boundary of VALIDATION A2, paper section 6.2, Fig. 8).

Structured: nx x ny quads between x0 and x1, each split into two
counter-clockwise triangles; column i's nodes sit at x_i on lines running from
the cosine to the top. Physical groups: "all" (the surface: every node),
"bottom" (the cosine edge, dimension 1).

Plain python3, no gmsh module:
  python3 scripts/make_sine_boundary_mesh.py inputs/meshes/sine_boundary.msh
  python3 scripts/make_sine_boundary_mesh.py OUT --x0 -0.1 --x1 0.6 --y0 0.535 --nx 140
"""
import argparse
import math


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--x0", type=float, default=-0.1, help="left end (m)")
    ap.add_argument("--x1", type=float, default=0.6, help="right end (m)")
    ap.add_argument("--y0", type=float, default=0.535, help="mean line of the cosine contour (m)")
    ap.add_argument("--amplitude", type=float, default=1.0 / 40.0, help="A (m)")
    ap.add_argument("--wavelength", type=float, default=0.1, help="(m)")
    ap.add_argument("--height", type=float, default=0.5, help="H: top at y0 + H (m)")
    ap.add_argument("--nx", type=int, default=140, help="elements along x")
    ap.add_argument("--ny", type=int, default=10, help="elements from the contour to the top")
    a = ap.parse_args()

    nx, ny = a.nx, a.ny
    k = 2.0 * math.pi / a.wavelength
    top = a.y0 + a.height

    def tag(i, j):  # node tag, 1-based, column-major
        return 1 + i * (ny + 1) + j

    nodes = []
    for i in range(nx + 1):
        x = a.x0 + (a.x1 - a.x0) * i / nx
        yb = a.y0 + a.amplitude * math.cos(k * x)
        for j in range(ny + 1):
            nodes.append((tag(i, j), x, yb + (top - yb) * j / ny))
    tris = []
    for i in range(nx):
        for j in range(ny):
            p00, p10, p11, p01 = tag(i, j), tag(i + 1, j), tag(i + 1, j + 1), tag(i, j + 1)
            tris.append((p00, p10, p11))
            tris.append((p00, p11, p01))
    bottom = [(tag(i, 0), tag(i + 1, 0)) for i in range(nx)]

    xs = [n[1] for n in nodes]
    ys = [n[2] for n in nodes]
    box = (min(xs), min(ys), 0.0, max(xs), max(ys), 0.0)
    with open(a.out, "w", encoding="ascii") as f:
        w = f.write
        w("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n")
        w('$PhysicalNames\n2\n1 1 "bottom"\n2 2 "all"\n$EndPhysicalNames\n')
        # Entities: one curve (the cosine edge, physical 1), one surface (physical 2).
        w("$Entities\n0 1 1 0\n")
        w("1 %.17g %.17g %.17g %.17g %.17g %.17g 1 1 0\n" % box)
        w("1 %.17g %.17g %.17g %.17g %.17g %.17g 1 2 1 1\n" % box)
        w("$EndEntities\n")
        # Every node in the surface's block.
        w("$Nodes\n1 %d 1 %d\n2 1 0 %d\n" % (len(nodes), len(nodes), len(nodes)))
        for t, _, _ in nodes:
            w("%d\n" % t)
        for _, x, y in nodes:
            w("%.17g %.17g 0\n" % (x, y))
        w("$EndNodes\n")
        ne = len(bottom) + len(tris)
        w("$Elements\n2 %d 1 %d\n" % (ne, ne))
        w("1 1 1 %d\n" % len(bottom))
        e = 1
        for p, q in bottom:
            w("%d %d %d\n" % (e, p, q))
            e += 1
        w("2 1 2 %d\n" % len(tris))
        for p, q, r in tris:
            w("%d %d %d %d\n" % (e, p, q, r))
            e += 1
        w("$EndElements\n")


if __name__ == "__main__":
    main()
