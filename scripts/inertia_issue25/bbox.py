# Issue 25 evaluation helper: prints the object-frame bounding box of a shared tool: lo hi (m)
import json, struct, sys, math
d = json.load(open(sys.argv[1])); base = sys.argv[1].rsplit('/', 1)[0]
b = open(base + '/' + d['mesh'], 'rb').read()
i = b.index(b'end_header'); end = b.index(b'\n', i) + 1
nv = int([l for l in b[:end].decode().split('\n') if l.startswith('element vertex')][0].split()[-1])
s = d['scale']; p = d['object_in_mesh']['position']; w, x, y, z = d['object_in_mesh']['quaternion']
R = [[1-2*(y*y+z*z), 2*(x*y-w*z), 2*(x*z+w*y)], [2*(x*y+w*z), 1-2*(x*x+z*z), 2*(y*z-w*x)], [2*(x*z-w*y), 2*(y*z+w*x), 1-2*(x*x+y*y)]]
lo = [1e9]*3; hi = [-1e9]*3
for i in range(nv):
    v = struct.unpack_from('<3f', b, end + 12*i)
    u = [s*v[j] - p[j] for j in range(3)]
    o = [sum(R[j][i2]*u[j] for j in range(3)) for i2 in range(3)]  # R^T u
    lo = [min(lo[k], o[k]) for k in range(3)]; hi = [max(hi[k], o[k]) for k in range(3)]
print(' '.join('%.4f' % x for x in lo + hi), '%.4f' % math.dist(lo, hi))
