"""Readers for sphseg output: HDF5 snapshots and diagnostics.csv.

Snapshot layout: attributes Time, Step, Dimension, NumPart_Total on /Header;
datasets under /Particles (Coordinates N x 3, Concentration, Kind (0 material,
1 dummy), ParticleIDs, Volume, BoundaryClass).
"""
import glob
import os

import h5py
import numpy as np

MATERIAL = 0


def _attr(value):
    """HDF5 attribute as a Python scalar where it is a one-element array."""
    arr = np.asarray(value)
    return arr.item() if arr.size == 1 else arr


def read_snapshot(path):
    """Read a snapshot: dict of /Particles arrays plus /Header attributes."""
    out = {"path": str(path)}
    with h5py.File(path, "r") as f:
        for key, value in f["Header"].attrs.items():
            out[key] = _attr(value)
        for key, dset in f["Particles"].items():
            out[key] = dset[()]
    return out


def snapshot_time(path):
    """Header Time of a snapshot without reading the particle data."""
    with h5py.File(path, "r") as f:
        return float(_attr(f["Header"].attrs["Time"]))


def list_snapshots(outdir):
    """Snapshot paths in OUTDIR, sorted by their number."""
    paths = glob.glob(os.path.join(outdir, "snapshot_*.h5"))
    number = lambda p: int(os.path.basename(p)[len("snapshot_"):-len(".h5")])
    return sorted((p for p in paths if _is_numbered(p)), key=number)


def _is_numbered(path):
    """True for snapshot_<digits>.h5 (skips temporaries and other files)."""
    stem = os.path.basename(path)[len("snapshot_"):-len(".h5")]
    return stem.isdigit()


def row_profile(snap, dr):
    """Row-averaged C of material particles: (y_rows, C_mean_rows).

    Shear-box material particles keep y = (j + 1/2) dr (horizontal motion
    only), so rows are grouped by j = round(y/dr - 1/2).  Rows without
    material particles are dropped.
    """
    mat = np.asarray(snap["Kind"]) == MATERIAL
    y = np.asarray(snap["Coordinates"])[mat, 1]
    C = np.asarray(snap["Concentration"])[mat]
    j = np.rint(y / dr - 0.5).astype(np.int64)
    j0 = j.min()
    count = np.bincount(j - j0)
    total = np.bincount(j - j0, weights=C)
    rows = np.nonzero(count)[0]
    return (rows + j0 + 0.5) * dr, total[rows] / count[rows]


# The per-particle fields two runs of one scene are compared on (tests).
COMPARE_FIELDS = ("Coordinates", "Velocities", "Stress", "Concentration", "ShearRate", "Normal", "Psi", "Volume")


def max_field_difference(ref, other, fields=COMPARE_FIELDS):
    """max over fields of max|other - ref| / max|ref|, for two snapshots (dicts
    of read_snapshot) holding the same particles in the same order; fields
    missing from ref are skipped."""
    worst = 0.0
    for f in fields:
        if f not in ref:
            continue
        a = np.asarray(ref[f])
        scale = max(float(np.max(np.abs(a))), 1e-300)
        worst = max(worst, float(np.max(np.abs(np.asarray(other[f]) - a))) / scale)
    return worst


def read_diagnostics(outdir):
    """diagnostics.csv as a dict of 1D numpy arrays keyed by column name
    (diagnostics.csv.part while the run is still going)."""
    path = os.path.join(outdir, "diagnostics.csv")
    if not os.path.exists(path) and os.path.exists(path + ".part"):
        path += ".part"
    data = np.genfromtxt(path, delimiter=",", names=True)
    return {name: np.atleast_1d(data[name]) for name in data.dtype.names}
