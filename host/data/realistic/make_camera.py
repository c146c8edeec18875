#!/usr/bin/env python3
"""Regenerate the camera-view shapes in host/data/realistic/ from the packages they come from.

These are the shapes added with the camera-view families (`camera_only` in
host/src/real_shapes.rs): anatomical surfaces of the kind a surgical robot registers.
The plane-cut families keep the ten shapes that make.py writes.

Needs Python 3, numpy and scikit-image (marching cubes, labelling and a Gaussian filter for
the two surfaces extracted from MRI volumes); it reuses make.py's archive reader, sampler,
normaliser and PLY writer. Not run in CI.

The inputs are the package files themselves, fetched with the ordinary clients:

    apt-get download mricron-data=1.2.20211006+dfsg-4            # Debian 12
    pip download --no-deps mne==1.13.2
    pip download --no-deps dm-control==1.0.52

Then:

    python3 make_camera.py --mricron mricron-data_1.2.20211006+dfsg-4_all.deb \
        --mne mne-1.13.2-py3-none-any.whl --dm-control dm_control-1.0.52-py3-none-any.whl \
        --out host/data/realistic

For every shape, with rng = numpy.random.default_rng(seed) (seeds go on from make.py's,
12 onwards, so that every seed in manifest.toml is distinct):
  * mesh sources (STL, FIF): the mesh as stored (STL vertices welded where bit-identical);
  * volume sources (NIfTI): the surface is extracted as below, in millimetres;
  * 20,000 points sampled uniformly by area, centred on their bounding box, scaled to a
    bounding-box diagonal of 1.0, written as PLY binary_little_endian 1.0 float32 x y z
    (make.py's sample_surface / normalise / write_ply).

Surface extraction from a volume (skin of the head, surface of the brain):
  the volume is cropped to the slices z >= z_from (colin_head: 60, i.e. MNI z >= -11 mm,
  just above the orbits: the template's field of view cuts the face and the lower head, and
  below that level the skin does not close around the orbits and sinuses);
  mask = intensity > threshold; keep the largest 6-connected component; for the head, close
  it with a ball of radius 2 voxels; fill its cavities (background components that do not
  touch the volume's border; for the head also in every 2-D slice); pad by 2 voxels; smooth
  the 0/1 mask with a Gaussian (sigma in voxels); marching cubes at level 0.5 (Lewiner,
  skimage.measure.marching_cubes); vertices scaled by the voxel size. Where the region
  touches a face of the volume (the scanner's field of view cuts the head), cavities cut
  open by that face are filled as well, and the surface is left open there: the triangles
  within 2 voxels of that face (the flat cap and its rounded rim) are dropped.
"""
import argparse
import gzip
import io
import os
import sys
import tarfile
import zipfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make import N_POINTS, read_ar_member, sample_surface, normalise, write_ply  # noqa: E402

MRICRON_DIR = 'usr/share/mricron/templates/'
MNE_DIR = 'mne/data/fsaverage/'
DOG_DIR = 'dm_control/suite/dog_assets/'
FIRST_SEED = 12  # make.py uses seeds 0..11

# (name, source, path inside the source, extraction parameters); the order fixes the seeds.
SHAPES = [
    ('colin_head', 'mricron', MRICRON_DIR + 'ch2.nii.gz',
     dict(threshold=30, sigma=1.0, seal=2, z_from=60, slices=True)),
    ('colin_cortex', 'mricron', MRICRON_DIR + 'ch2bet.nii.gz',
     dict(threshold=75, sigma=0.7, seal=0, z_from=0, slices=False)),
    ('fsaverage_head', 'mne', MNE_DIR + 'fsaverage-head.fif', None),
    ('dog_skull', 'dm_control', DOG_DIR + 'BONEMergedSkull.stl', None),
    ('dog_vertebra', 'dm_control', DOG_DIR + 'BONEL_3.stl', None),
    ('dog_pelvis', 'dm_control', DOG_DIR + 'BONEPelvis.stl', None),
]

# ---------------------------------------------------------------- archives


class Sources:
    def __init__(self, mricron, mne, dm_control):
        self.paths = {'mricron': mricron, 'mne': mne, 'dm_control': dm_control}
        self._deb = None

    def read(self, source, path):
        if source == 'mricron':
            if self._deb is None:
                raw = read_ar_member(self.paths['mricron'], 'data.tar.xz')
                self._deb = tarfile.open(fileobj=io.BytesIO(raw))
            for m in self._deb.getmembers():
                if m.name.lstrip('./') == path:
                    return self._deb.extractfile(m).read()
            raise KeyError(path)
        with zipfile.ZipFile(self.paths[source]) as z:
            return z.read(path)

# ---------------------------------------------------------------- readers


def read_stl(data):
    """Binary STL; vertices welded where bit-identical."""
    if data[:5] == b'solid' and b'facet' in data[:512]:
        raise ValueError('ASCII STL not supported')
    n = int(np.frombuffer(data, '<u4', 1, 80)[0])
    dt = np.dtype([('normal', '<f4', 3), ('v', '<f4', (3, 3)), ('attr', '<u2')])
    corners = np.frombuffer(data, dt, n, 84)['v'].reshape(-1, 3).astype(np.float64)
    V, inv = np.unique(corners, axis=0, return_inverse=True)
    return V, inv.reshape(-1, 3).astype(np.int64)


def read_fif_surface(data):
    """The first BEM surface of a FIF file: FIFF_BEM_SURF_NODES (3105, float matrix, metres)
    and FIFF_BEM_SURF_TRIANGLES (3106, int matrix, 1-based). FIF tags are big-endian
    (kind, type, size, next) headers followed by `size` bytes; a matrix stores its elements,
    then its dimensions (last first), then their count."""
    pos, found = 0, {}
    while pos + 16 <= len(data):
        kind, typ, size, _next = (int(x) for x in np.frombuffer(data, '>i4', 4, pos))
        if kind in (3105, 3106) and kind not in found:
            body = data[pos + 16:pos + 16 + size]
            ndim = int(np.frombuffer(body[-4:], '>i4')[0])
            dims = np.frombuffer(body[-4 - 4 * ndim:-4], '>i4')[::-1]
            dt = {3: '>i4', 4: '>f4', 5: '>f8'}[typ & 0xFFFF]
            found[kind] = np.frombuffer(body[:-4 - 4 * ndim], dt).reshape(dims)
        pos += 16 + size
    return found[3105].astype(np.float64), found[3106].astype(np.int64) - 1


def read_nifti(data):
    """NIfTI-1 (.nii.gz): the volume as float64 (x fastest on disk) and the voxel size."""
    if data[:2] == b'\x1f\x8b':
        data = gzip.decompress(data)
    if int(np.frombuffer(data, '<i4', 1, 0)[0]) != 348:
        raise ValueError('not a little-endian NIfTI-1 file')
    dim = np.frombuffer(data, '<i2', 8, 40)
    datatype = int(np.frombuffer(data, '<i2', 1, 70)[0])
    pixdim = np.frombuffer(data, '<f4', 8, 76)
    offset = int(np.frombuffer(data, '<f4', 1, 108)[0])
    dt = {2: '<u1', 4: '<i2', 8: '<i4', 16: '<f4', 64: '<f8', 512: '<u2'}[datatype]
    shape = tuple(int(d) for d in dim[1:1 + dim[0]])
    vol = np.frombuffer(data, dt, int(np.prod(shape)), offset).reshape(shape, order='F')
    return vol.astype(np.float64), np.array(pixdim[1:4], dtype=np.float64)


def _holes(region):
    """Background components of a 2-D or 3-D boolean array that do not touch its border."""
    from skimage.measure import label

    bg = label(~region, connectivity=1)
    border = np.unique(np.concatenate(
        [np.take(bg, side, axis=axis).ravel() for axis in range(bg.ndim) for side in (0, -1)]))
    return ~np.isin(bg, border) & ~region


def volume_surface(vol, spacing, threshold, sigma, seal, z_from, slices):
    """The outer iso-surface of the largest bright region (see the module docstring)."""
    vol = vol[:, :, z_from:]
    from skimage.filters import gaussian
    from skimage.measure import label, marching_cubes
    from skimage.morphology import ball, closing

    lab = label(vol > threshold, connectivity=1)
    sizes = np.bincount(lab.ravel())
    sizes[0] = 0
    mask = lab == int(np.argmax(sizes))
    # Faces of the volume that the region touches: the field of view cuts it there.
    cut = [(axis, side) for axis in range(3) for side in (0, -1)
           if np.take(mask, side, axis=axis).any()]
    # Close the region with a ball of radius `seal` voxels (if seal > 0), then fill its
    # cavities: background components that do not reach the border, in 3-D and, if
    # `slices`, in every 2-D slice along x, y and z too (the skull is dark in T1 and leaks
    # to the outside through small gaps in the skin), with the cut faces counted as closed.
    # (Not for the brain: slice-wise filling would close its sulci.)
    closed = np.pad(closing(mask, ball(seal)) if seal else mask, 1)
    for axis, side in cut:
        idx = [slice(None)] * 3
        idx[axis] = side
        closed[tuple(idx)] = True
    holes = _holes(closed)
    for axis in range(3 if slices else 0):
        for k in range(closed.shape[axis]):
            idx = [slice(None)] * 3
            idx[axis] = k
            holes[tuple(idx)] |= _holes(closed[tuple(idx)])
    mask = (closed | holes)[1:-1, 1:-1, 1:-1]
    pad = 2
    smooth = gaussian(np.pad(mask, pad).astype(np.float64), sigma=sigma, mode='constant',
                      preserve_range=True)
    V, F, _n, _v = marching_cubes(smooth, level=0.5)
    # Drop the caps that close the surface on the cut faces (triangles whose centroid lies
    # within 2 voxels of a cut face): the surface ends open there, as a scan would.
    C = V[F].mean(1)
    keep = np.ones(len(F), bool)
    for axis, side in cut:
        if side == 0:
            keep &= C[:, axis] > pad + 2.0
        else:
            keep &= C[:, axis] < pad + mask.shape[axis] - 1 - 2.0
    F = F[keep]
    used = np.unique(F)
    remap = np.full(len(V), -1, np.int64)
    remap[used] = np.arange(len(used))
    return (V[used] - pad) * spacing, remap[F]


def load(src, source, path, params):
    data = src.read(source, path)
    if path.endswith('.stl'):
        return read_stl(data)
    if path.endswith('.fif'):
        return read_fif_surface(data)
    if path.endswith('.nii.gz'):
        vol, spacing = read_nifti(data)
        return volume_surface(vol, spacing, **params)
    raise ValueError(path)

# ---------------------------------------------------------------- main


def make(src, out, only=None):
    os.makedirs(out, exist_ok=True)
    for index, (name, source, path, params) in enumerate(SHAPES):
        if only and name not in only:
            continue
        rng = np.random.default_rng(seed=FIRST_SEED + index)
        V, F = load(src, source, path, params)
        P = normalise(sample_surface(V, F, N_POINTS, rng))
        write_ply(os.path.join(out, name + '.ply'), P)
        print('%-16s seed %2d %6d points  (%d vertices, %d triangles)'
              % (name, FIRST_SEED + index, len(P), len(np.unique(F)), len(F)))


if __name__ == '__main__':
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--mricron', required=True, help='mricron-data_1.2.20211006+dfsg-4_all.deb')
    ap.add_argument('--mne', required=True, help='mne-1.13.2 wheel')
    ap.add_argument('--dm-control', required=True, help='dm_control-1.0.52 wheel')
    ap.add_argument('--out', default=os.path.dirname(os.path.abspath(__file__)))
    ap.add_argument('--only', nargs='*', help='names to make (default: all)')
    a = ap.parse_args()
    make(Sources(a.mricron, a.mne, a.dm_control), a.out, a.only)
    sys.exit(0)
