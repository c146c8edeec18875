#!/usr/bin/env python3
"""Regenerate the PLY point sets in host/data/realistic/ from the packages they come from.

Needs Python 3 and numpy only (no mesh library: the OFF/PLY readers are below). Not run in CI.

The inputs are the package files themselves, fetched with the ordinary clients:

    apt-get download libcgal-demo=5.5.1-2          # libcgal-demo_5.5.1-2_all.deb (Debian 12)
    pip download --no-deps pymeshlab==2025.7.post1  # pymeshlab-2025.7.post1-cp311-...whl
    pip download --no-deps pyvista==0.49.2          # pyvista-0.49.2-py3-none-any.whl

Then:

    python3 make.py --deb libcgal-demo_5.5.1-2_all.deb \
        --pymeshlab pymeshlab-2025.7.post1-*.whl --pyvista pyvista-0.49.2-py3-none-any.whl \
        --out host/data/realistic

The script reads the mesh files straight out of the .deb (an `ar` archive holding
data.tar.xz, which holds usr/share/doc/libcgal-dev/data.tar.gz) and the wheels (zip files).

For every shape, with rng = numpy.random.default_rng(seed=index) (index = position in SHAPES):
  * a mesh: 20,000 points sampled uniformly by area (triangle chosen with probability
    proportional to its area, then a uniform point in it; polygons are fan-triangulated);
  * a point set (no faces): a random subset of 20,000 of its points (all if fewer);
  * then the bounding box of the points is centred at the origin and the points are scaled
    so that the bounding-box diagonal is 1.0;
  * written as PLY binary_little_endian 1.0, one element `vertex`, float32 x y z only.
"""
import argparse
import io
import os
import sys
import tarfile
import zipfile

import numpy as np

N_POINTS = 20000
CGAL_DATA = 'usr/share/doc/libcgal-dev/data.tar.gz'
PYMESHLAB_DIR = 'pymeshlab-2025.7.post1.data/purelib/pymeshlab/tests/sample_meshes/'

# (name, kind, source, path inside the source); the order fixes the seeds.
SHAPES = [
    ('bunny', 'scan', 'cgal', 'data/meshes/bunny00.off'),
    ('armadillo', 'scan', 'cgal', 'data/meshes/armadillo.off'),
    ('chinese_dragon', 'scan', 'cgal', 'data/meshes/ChineseDragon-10kv.off'),
    ('lion_head', 'scan', 'cgal', 'data/meshes/lion-head.off'),
    ('face_rangemap', 'scan', 'pymeshlab', PYMESHLAB_DIR + 'rangemaps/face000.ply'),
    ('b9_lidar', 'scan', 'cgal', 'data/meshes/b9.ply'),
    ('fandisk', 'cad', 'cgal', 'data/meshes/fandisk.off'),
    ('joint', 'cad', 'cgal', 'data/meshes/joint.off'),
    ('mech_holes_shark', 'cad', 'cgal', 'data/meshes/mech-holes-shark.off'),
    ('part', 'cad', 'cgal', 'data/meshes/part.off'),
    ('anchor', 'cad', 'cgal', 'data/meshes/anchor.off'),
    ('nut', 'cad', 'pyvista', 'pyvista/examples/nut.ply'),
]

# ---------------------------------------------------------------- archives

def read_ar_member(path, name):
    with open(path, 'rb') as f:
        data = f.read()
    if data[:8] != b'!<arch>\n':
        raise ValueError('%s is not an ar archive' % path)
    pos = 8
    while pos + 60 <= len(data):
        hdr = data[pos:pos + 60]
        member = hdr[:16].decode().strip().rstrip('/')
        size = int(hdr[48:58].decode().strip())
        if member == name:
            return data[pos + 60:pos + 60 + size]
        pos += 60 + size + (size & 1)
    raise KeyError('%s not in %s' % (name, path))


class Sources:
    def __init__(self, deb, pymeshlab, pyvista):
        self.deb, self.pymeshlab, self.pyvista = deb, pymeshlab, pyvista
        self._cgal = None

    def cgal(self):
        if self._cgal is None:
            outer = tarfile.open(fileobj=io.BytesIO(read_ar_member(self.deb, 'data.tar.xz')))
            inner = None
            for m in outer.getmembers():
                if m.name.lstrip('./') == CGAL_DATA:
                    inner = outer.extractfile(m).read()
            if inner is None:
                raise KeyError(CGAL_DATA)
            self._cgal = tarfile.open(fileobj=io.BytesIO(inner), mode='r:gz')
        return self._cgal

    def read(self, source, path):
        if source == 'cgal':
            t = self.cgal()
            return t.extractfile(t.getmember(path)).read()
        whl = {'pymeshlab': self.pymeshlab, 'pyvista': self.pyvista}[source]
        with zipfile.ZipFile(whl) as z:
            return z.read(path)

# ---------------------------------------------------------------- readers

_PLY_TYPES = {
    'char': 'i1', 'int8': 'i1', 'uchar': 'u1', 'uint8': 'u1',
    'short': 'i2', 'int16': 'i2', 'ushort': 'u2', 'uint16': 'u2',
    'int': 'i4', 'int32': 'i4', 'uint': 'u4', 'uint32': 'u4',
    'float': 'f4', 'float32': 'f4', 'double': 'f8', 'float64': 'f8',
}


def _fan(poly):
    return [(poly[0], poly[i], poly[i + 1]) for i in range(1, len(poly) - 1)]


def read_off(data):
    lines = []
    for ln in data.decode('latin-1').splitlines():
        ln = ln.split('#', 1)[0].strip()
        if ln:
            lines.append(ln)
    head = lines[0].split()
    if not head[0].endswith('OFF'):
        raise ValueError('not an OFF file')
    rest, i = head[1:], 1
    if not rest:
        rest, i = lines[1].split(), 2
    nv, nf = int(rest[0]), int(rest[1])
    V = np.array([[float(t) for t in lines[i + k].split()[:3]] for k in range(nv)])
    F = []
    for k in range(nf):
        t = lines[i + nv + k].split()
        n = int(t[0])
        F.extend(_fan([int(x) for x in t[1:1 + n]]))
    return V, np.array(F, dtype=np.int64).reshape(-1, 3)


def read_ply(data):
    end = data.index(b'end_header') + len(b'end_header')
    end = data.index(b'\n', end) + 1
    fmt, elements = None, []
    for ln in data[:end].decode('latin-1').splitlines():
        t = ln.split()
        if not t:
            continue
        if t[0] == 'format':
            fmt = t[1]
        elif t[0] == 'element':
            elements.append((t[1], int(t[2]), []))
        elif t[0] == 'property':
            if t[1] == 'list':
                elements[-1][2].append((t[4], 'list', _PLY_TYPES[t[2]], _PLY_TYPES[t[3]]))
            else:
                elements[-1][2].append((t[2], _PLY_TYPES[t[1]]))
    body = data[end:]
    V, F = None, []
    if fmt == 'ascii':
        toks, pos = body.split(), 0
        for name, count, props in elements:
            for _ in range(count):
                row = {}
                for p in props:
                    if p[1] == 'list':
                        n = int(toks[pos]); pos += 1
                        row[p[0]] = [int(x) for x in toks[pos:pos + n]]; pos += n
                    else:
                        row[p[0]] = float(toks[pos]); pos += 1
                if name == 'vertex':
                    if V is None:
                        V = []
                    V.append((row['x'], row['y'], row['z']))
                elif name == 'face':
                    F.extend(_fan(row[[p[0] for p in props if p[1] == 'list'][0]]))
        V = np.array(V, dtype=np.float64)
    else:
        e = '<' if fmt == 'binary_little_endian' else '>'
        pos = 0
        for name, count, props in elements:
            if all(p[1] != 'list' for p in props):
                dt = np.dtype([(p[0], e + p[1]) for p in props])
                arr = np.frombuffer(body, dtype=dt, count=count, offset=pos)
                pos += dt.itemsize * count
                if name == 'vertex':
                    V = np.stack([arr['x'], arr['y'], arr['z']], 1).astype(np.float64)
            else:
                for _ in range(count):
                    for p in props:
                        if p[1] == 'list':
                            cdt, idt = np.dtype(e + p[2]), np.dtype(e + p[3])
                            n = int(np.frombuffer(body, cdt, 1, pos)[0]); pos += cdt.itemsize
                            idx = np.frombuffer(body, idt, n, pos); pos += idt.itemsize * n
                            if name == 'face':
                                F.extend(_fan([int(x) for x in idx]))
                        else:
                            pos += np.dtype(p[1]).itemsize
    return V, np.array(F, dtype=np.int64).reshape(-1, 3)


def read_mesh(path, data):
    return read_off(data) if path.lower().endswith('.off') else read_ply(data)

# ---------------------------------------------------------------- sampling and output

def sample_surface(V, F, n, rng):
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    tri = rng.choice(len(F), size=n, p=area / area.sum())
    u, v = rng.random(n), rng.random(n)
    flip = u + v > 1.0
    u[flip], v[flip] = 1.0 - u[flip], 1.0 - v[flip]
    return a[tri] + u[:, None] * (b[tri] - a[tri]) + v[:, None] * (c[tri] - a[tri])


def normalise(P):
    lo, hi = P.min(0), P.max(0)
    return (P - (lo + hi) / 2.0) / np.linalg.norm(hi - lo)


def write_ply(path, P):
    P = np.ascontiguousarray(P, dtype='<f4')
    if not np.isfinite(P).all():
        raise ValueError('non-finite value in %s' % path)
    header = ('ply\nformat binary_little_endian 1.0\nelement vertex %d\n'
              'property float x\nproperty float y\nproperty float z\nend_header\n' % len(P))
    with open(path, 'wb') as f:
        f.write(header.encode('ascii'))
        f.write(P.tobytes())


def make(src, out):
    os.makedirs(out, exist_ok=True)
    for index, (name, kind, source, path) in enumerate(SHAPES):
        rng = np.random.default_rng(seed=index)
        V, F = read_mesh(path, src.read(source, path))
        if len(F):
            P = sample_surface(V, F, N_POINTS, rng)
        else:
            P = V[rng.permutation(len(V))[:N_POINTS]] if len(V) > N_POINTS else V
        P = normalise(P)
        write_ply(os.path.join(out, name + '.ply'), P)
        print('%-18s %-4s %6d points  (%d vertices, %d triangles)' % (name, kind, len(P), len(V), len(F)))


if __name__ == '__main__':
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--deb', required=True, help='libcgal-demo_5.5.1-2_all.deb')
    ap.add_argument('--pymeshlab', required=True, help='pymeshlab-2025.7.post1 wheel')
    ap.add_argument('--pyvista', required=True, help='pyvista-0.49.2 wheel')
    ap.add_argument('--out', default=os.path.dirname(os.path.abspath(__file__)))
    a = ap.parse_args()
    make(Sources(a.deb, a.pymeshlab, a.pyvista), a.out)
    sys.exit(0)
