# Issue 25 evaluation helper. usage: add_noise.py in.csv out.csv seed sa sdw sf st  [pm mass x y z]  (Gaussian noise on measured columns)
import csv, random, sys, math
inp, out, seed = sys.argv[1], sys.argv[2], int(sys.argv[3])
sa, sdw, sf, st = map(float, sys.argv[4:8])
pm = None
if len(sys.argv) > 8: pm = list(map(float, sys.argv[8:12]))
rng = random.Random(seed)
rows = list(csv.reader(open(inp)))
h = rows[0]; ix = {n: i for i, n in enumerate(h)}
def cross(a, b): return [a[1]*b[2]-a[2]*b[1], a[2]*b[0]-a[0]*b[2], a[0]*b[1]-a[1]*b[0]]
def rot_t(q, v):  # R^T v, q = w,x,y,z rotating object->world
    w, x, y, z = q; n = math.sqrt(w*w+x*x+y*y+z*z); w, x, y, z = w/n, x/n, y/n, z/n
    R = [[1-2*(y*y+z*z), 2*(x*y-w*z), 2*(x*z+w*y)], [2*(x*y+w*z), 1-2*(x*x+z*z), 2*(y*z-w*x)], [2*(x*z-w*y), 2*(y*z+w*x), 1-2*(x*x+y*y)]]
    return [sum(R[i][j]*v[i] for i in range(3)) for j in range(3)]
with open(out, 'w', newline='') as f:
    wr = csv.writer(f); wr.writerow(h)
    for r in rows[1:]:
        v = [float(x) for x in r]
        if pm:
            m, p = pm[0], pm[1:4]
            q = [v[ix[c]] for c in ('qw','qx','qy','qz')]
            a = [v[ix['ax']], v[ix['ay']], v[ix['az']] + 9.81]
            amg = rot_t(q, a)
            w = [v[ix[c]] for c in ('wx','wy','wz')]; dw = [v[ix[c]] for c in ('dwx','dwy','dwz')]
            acc = [amg[i] + cross(dw, p)[i] + cross(w, cross(w, p))[i] for i in range(3)]
            F = [m*x for x in acc]; T = cross(p, F)
            for i, c in enumerate(('fx','fy','fz')): v[ix[c]] += F[i]
            for i, c in enumerate(('tx','ty','tz')): v[ix[c]] += T[i]
        for cols, s in ((('ax','ay','az'), sa), (('dwx','dwy','dwz'), sdw), (('fx','fy','fz'), sf), (('tx','ty','tz'), st)):
            for c in cols: v[ix[c]] += rng.gauss(0, s) if s > 0 else 0
        wr.writerow(['%.17g' % x for x in v])
