"""Readers for sphseg output: HDF5 snapshots and diagnostics.csv.

Snapshot layout: attributes Time, Step, Dimension, NumPart_Total on /Header;
datasets under /Particles (Coordinates N x 3, Concentration, Kind (0 material,
1 dummy), ParticleIDs, Volume, BoundaryClass).
"""
import glob
import math
import os
import sys

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


def wall_ids(snap):
    """The container's wall primitives of a snapshot (header attribute Walls,
    "1 base, 2 xlo, ..."), as {name: id}; the Wall field holds the id."""
    out = {}
    for item in str(snap.get("Walls", "")).split(","):
        if item.strip():
            k, name = item.split()
            out[name] = int(k)
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


class MissingField(KeyError):
    """A field a comparison needs is missing from a snapshot."""


def max_field_difference(ref, other, fields=COMPARE_FIELDS):
    """max over fields of max|other - ref| / max|ref|, for two snapshots (dicts
    of read_snapshot) holding the same particles in the same order. A field
    missing from either snapshot raises MissingField (a comparison that
    silently skipped it would pass whatever it holds)."""
    worst = 0.0
    for f in fields:
        for name, s in (("reference", ref), ("other", other)):
            if f not in s:
                raise MissingField("field %s missing from the %s snapshot %s" % (f, name, s.get("path", "?")))
        a = np.asarray(ref[f])
        scale = max(float(np.max(np.abs(a))), 1e-300)
        worst = max(worst, float(np.max(np.abs(np.asarray(other[f]) - a))) / scale)
    return worst


def read_diagnostics(outdir, partial=False):
    """diagnostics.csv as a dict of 1D numpy arrays keyed by column name.
    A finished run renames diagnostics.csv.part to diagnostics.csv; only with
    partial=True (a run still going, or one that stopped) is the .part file
    read, and then it is said on stderr."""
    path = os.path.join(outdir, "diagnostics.csv")
    if not os.path.exists(path):
        if not (partial and os.path.exists(path + ".part")):
            raise FileNotFoundError("%s: no diagnostics.csv%s" % (
                outdir, " (only a .part file: the run did not finish; partial=True reads it)"
                if os.path.exists(path + ".part") else ""))
        path += ".part"
        print("note: reading %s (the run has not finished)" % path, file=sys.stderr)
    data = np.genfromtxt(path, delimiter=",", names=True)
    return {name: np.atleast_1d(data[name]) for name in data.dtype.names}


def small_volume(s):
    """sum C_i V_i over the material particles of a snapshot (read_snapshot),
    correctly rounded (math.fsum), as the code's compensated sum (src/core/ksum.h)
    is to one unit round-off: the two agree to ~2e-16 in any particle order."""
    m = np.asarray(s["Kind"]) == MATERIAL
    return math.fsum(np.asarray(s["Concentration"], dtype=float)[m] * np.asarray(s["Volume"], dtype=float)[m])


def conservation(outdir):
    """The conservation of sum C_i V_i checked independently of the code's
    own drift: S(t) recomputed from every snapshot of OUTDIR, and
    diagnostics.csv held to it. Returns a dict:
      drift     max |S(t) - S(0)| / |S(0)| over the snapshots;
      column    max relative difference between the small_volume column and
                S at the snapshot times (every snapshot time has a row);
      reported  max |small_volume_drift - (small_volume - small_volume[0]) /
                small_volume[0]|: the drift column against its definition on
                the small_volume column (the same double operations: 0 when
                the column is what the code computed);
      snapshots the number of snapshots."""
    paths = list_snapshots(outdir)
    if not paths:
        raise FileNotFoundError("%s: no snapshots" % outdir)
    dg = read_diagnostics(outdir)
    sv, t = np.asarray(dg["small_volume"], dtype=float), np.asarray(dg["time"], dtype=float)
    S0, drift, column = None, 0.0, 0.0
    for p in paths:
        s = read_snapshot(p)
        S = small_volume(s)
        S0 = S if S0 is None else S0
        drift = max(drift, abs(S - S0) / abs(S0))
        k = np.nonzero(np.abs(t - float(s["Time"])) <= 1e-9 * max(1.0, abs(float(s["Time"]))))[0]
        if len(k) == 0:
            raise RuntimeError("%s: no diagnostics row at the snapshot time %.17g" % (outdir, float(s["Time"])))
        column = max(column, abs(sv[k[0]] - S) / abs(S))
    reported = float(np.max(np.abs(np.asarray(dg["small_volume_drift"], dtype=float) - (sv - sv[0]) / sv[0])))
    return {"drift": drift, "column": column, "reported": reported, "snapshots": len(paths)}
