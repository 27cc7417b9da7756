# Two-material mallet: steel head on a wooden handle (two closed boxes, one face colour each), object frame = grip, metres.
import json, sys
OUT = sys.argv[1] if len(sys.argv) > 1 else '.'
parts = [  # (lo, hi, density, colour)
    ((-0.015, -0.01, -0.05), (0.015, 0.01, 0.20), 600.0, (150, 100, 50)),
    ((-0.05, -0.02, 0.20), (0.05, 0.02, 0.24), 7850.0, (90, 90, 100)),
]
verts, faces = [], []
quads = [(0,2,3,1),(4,5,7,6),(0,1,5,4),(2,6,7,3),(0,4,6,2),(1,3,7,5)]  # outward for corner index bits x(4) y(2) z(1)
M = 0; S = [0,0,0]; I2 = [[0]*3 for _ in range(3)]
for lo, hi, rho, col in parts:
    base = len(verts)
    for i in range(8):
        verts.append((hi[0] if i & 4 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 1 else lo[2]))
    for q in quads:
        faces.append(((base+q[0], base+q[2], base+q[1]), col)); faces.append(((base+q[0], base+q[3], base+q[2]), col))
    d = [hi[i]-lo[i] for i in range(3)]; c = [(hi[i]+lo[i])/2 for i in range(3)]
    m = rho*d[0]*d[1]*d[2]; M += m
    for i in range(3): S[i] += m*c[i]
    # second moment about origin: sum m (x_i x_j)
    for i in range(3):
        for j in range(3):
            I2[i][j] += m*c[i]*c[j] + (m*d[i]**2/12 if i == j else 0)
com = [S[i]/M for i in range(3)]
C = [[I2[i][j] - M*com[i]*com[j] for j in range(3)] for i in range(3)]  # second moment about CoM
tr = C[0][0]+C[1][1]+C[2][2]
I = [[(tr if i == j else 0) - C[i][j] for j in range(3)] for i in range(3)]
json.dump({"mass": M, "com": com, "inertia_com": [I[0][0], I[1][1], I[2][2], I[0][1], I[0][2], I[1][2]]}, open(OUT + '/mallet.truth.json','w'), indent=1)
with open(OUT + '/mallet.ply','w') as f:
    f.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\nelement face %d\nproperty list uchar int vertex_indices\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n" % (len(verts), len(faces)))
    for v in verts: f.write("%.9g %.9g %.9g\n" % v)
    for (a,b,c), col in faces: f.write("3 %d %d %d %d %d %d\n" % (a,b,c,*col))
print(M, com)
