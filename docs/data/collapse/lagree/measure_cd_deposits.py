"""Final deposits of the contact-dynamics (CD) columns that Lagree et al. compare with,
as stored in the Basilisk sandbox (basilisk-wiki/sandbox/M1EMN/Exemples/Img/ShapeTime.A-0x.dat,
comphy-lab/basilisk-C @ c7be0ade). Columns: x (grain diameters, symmetric about 0), surface height (grains)."""
import numpy as np, sys
def blocks(fn):
    out=[];cur=[]
    for line in open(fn):
        s=line.split()
        if len(s)<2:
            if cur: out.append(np.array(cur)); cur=[]
            continue
        cur.append([float(s[0]),float(s[1])])
    if cur: out.append(np.array(cur))
    return out
def extent(x, thr):
    k = x[:,1] > thr
    dx = np.median(np.diff(x[:,0]))
    return x[k,0].min() - dx/2, x[k,0].max() + dx/2
for fn, aname in [("Exemples__Img__ShapeTime.A-01.dat","0.5"),("Exemples__Img__ShapeTime.A-04.dat","1.42"),("Exemples__Img__ShapeTime.A-03.dat","6.26")]:
    b = blocks(fn)
    x0 = b[0]; lo, hi = extent(x0, 0.0); R0 = (hi - lo)/2; H0 = x0[np.abs(x0[:,0]) < 0.8*R0, 1].mean()
    f = b[-1]
    print("a=%s file %s: %d blocks, last two identical: %s" % (aname, fn, len(b), np.array_equal(b[-1], b[-2])))
    print("   initial: R0 = %.1f d, H0 = %.1f d, a = H0/R0 = %.2f" % (R0, H0, H0/R0))
    for thr in (0.0, 1.5, 3.0):
        lo, hi = extent(f, thr); L = (hi - lo)/2
        print("   final, extent where h > %.1f d: half-length L = %.1f d (left %.1f, right %.1f) -> (L-R0)/R0 = %.2f (left %.2f, right %.2f)" % (
            thr, L, -lo, hi, (L-R0)/R0, (-lo-R0)/R0, (hi-R0)/R0))
    hc = f[np.abs(f[:,0]) < 3, 1].mean()
    print("   final height at the axis (|x| < 3 d): %.1f d -> H/R0 = %.2f, H/H0 = %.2f" % (hc, hc/R0, hc/H0))
