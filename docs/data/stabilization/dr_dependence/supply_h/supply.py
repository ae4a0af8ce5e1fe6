"""The bed's rotation and the layer's flux on the 2D EV drum's mid-chord (README.md beside this file).
Reads RUN.npz (material fields of the snapshots at 3 and 3.5 s, extracted on the device machine; not
kept) and RUN_used_params.yml. Ad hoc, kept as the record of how supply.txt was computed:
  /usr/bin/python3 supply.py RUNDIR/b05 RUNDIR/b025 > supply.txt"""
import sys, numpy as np, yaml
sys.path.insert(0, '.')
from tools.analysis import drum_analysis as da
def load(npz, par, t):
    d = np.load(npz); k = 't%g_' % t
    kind = d[k+'Kind']
    s = {'Time': t, 'Kind': kind, 'Coordinates': d[k+'Coordinates'], 'Velocities': d[k+'Velocities'],
         'Concentration': np.full(len(kind), 0.5), 'ShearRate': d[k+'ShearRate'], 'Volume': d[k+'Volume']}
    return da.Drum(None, par, snapshot=s), d[k+'Stress'][kind == 0]
def analyse(run, times, rbins):
    par = yaml.safe_load(open(run + '_used_params.yml'))
    R = par['Geometry']['radius']; W = -5 * 2 * np.pi / 60
    out = []
    for t in times:
        D, S = load(run + '.npz', par, t)
        x, v = D.x, D.v
        r = np.hypot(x[:, 0], x[:, 1])
        om = (x[:, 0] * v[:, 1] - x[:, 1] * v[:, 0]) / r ** 2 / W
        tng = np.array([D.n[1], -D.n[0]])
        s = (x - D.M) @ tng; dep = (x - D.M) @ D.n
        strip = np.abs(s) < 0.05 * R
        ut = v @ tng
        if np.mean(ut[strip & (dep < 2e-3)]) < 0: tng = -tng; ut = -ut
        rM = np.hypot(*D.M)
        lay = strip & (ut > 0)
        Q = np.sum(D.vol[lay] * ut[lay]) / (0.1 * R)
        Qb = -np.sum(D.vol[strip & (ut < 0)] * ut[strip & (ut < 0)]) / (0.1 * R)
        prof = []
        for lo, hi in zip(rbins[:-1], rbins[1:]):
            k = strip & (r >= lo) & (r < hi) & (dep > 0)
            prof.append(om[k].mean() if k.any() else np.nan)
        # whole bed, deep (r from axis), below y<-0.6R as drum_bed_rotation
        out.append((t, Q, Qb, rM, np.array(prof)))
    return out
rb = np.array([10, 12, 14, 16, 18, 20, 24, 28, 32, 34, 34.5, 35.01]) * 1e-3
for run in sys.argv[1:]:
    res = analyse(run, [3, 3.5], rb)
    Q = np.mean([o[1] for o in res]); Qb = np.mean([o[2] for o in res]); rM = np.mean([o[3] for o in res])
    print('%-22s Q layer %.4e  Q bed %.4e  rM %.3f mm  ' % (run.split('/')[-1], Q, Qb, rM * 1e3) )
    print('   omega/omega_wall by r(mm):', ' '.join('%g-%g:%.4f' % (a*1e3, b*1e3, p) for a, b, p in zip(rb[:-1], rb[1:], np.nanmean([o[4] for o in res], axis=0))))
