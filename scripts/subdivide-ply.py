#!/usr/bin/python3
"""A mesh of many triangles for timing the renders: a binary PLY (float x y z, uchar-int faces) split 1-to-4
(edge midpoints), then 1-to-6 (centroid and midpoints): 24 triangles for each.

    /usr/bin/python3 scripts/subdivide-ply.py in.ply out.ply
"""
import numpy as np, sys
def read(p):
    f=open(p,'rb'); h=b''
    while not h.endswith(b'end_header\n'): h+=f.readline()
    hd=h.decode(); nv=int(hd.split('element vertex ')[1].split()[0]); nf=int(hd.split('element face ')[1].split()[0])
    v=np.frombuffer(f.read(12*nv),dtype='<f4').reshape(nv,3).astype(np.float64)
    fd=np.frombuffer(f.read(13*nf),dtype=np.dtype([('n','u1'),('i','<i4',3)]))
    return v, fd['i'].astype(np.int64)
def write(p,v,t):
    with open(p,'wb') as f:
        f.write(f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\nproperty float x\nproperty float y\nproperty float z\nelement face {len(t)}\nproperty list uchar int vertex_indices\nend_header\n".encode())
        f.write(v.astype('<f4').tobytes())
        rec=np.zeros(len(t),dtype=np.dtype([('n','u1'),('i','<i4',3)])); rec['n']=3; rec['i']=t; f.write(rec.tobytes())
v,t=read(sys.argv[1])
# 1-to-4 with shared midpoints
e=np.sort(np.concatenate([t[:,[0,1]],t[:,[1,2]],t[:,[2,0]]]),axis=1)
u,inv=np.unique(e,axis=0,return_inverse=True); inv=inv.reshape(3,-1)
m=len(v)+inv; v=np.concatenate([v,(v[u[:,0]]+v[u[:,1]])/2])
a,b,c=t[:,0],t[:,1],t[:,2]; ab,bc,ca=m[0],m[1],m[2]
t=np.concatenate([np.stack([a,ab,ca],1),np.stack([ab,b,bc],1),np.stack([ca,bc,c],1),np.stack([ab,bc,ca],1)])
# 1-to-6: centroid and edge midpoints
e=np.sort(np.concatenate([t[:,[0,1]],t[:,[1,2]],t[:,[2,0]]]),axis=1)
u,inv=np.unique(e,axis=0,return_inverse=True); inv=inv.reshape(3,-1)
m=len(v)+inv; v=np.concatenate([v,(v[u[:,0]]+v[u[:,1]])/2])
g=len(v)+np.arange(len(t)); v=np.concatenate([v,(v[t[:,0]]+v[t[:,1]]+v[t[:,2]])/3])
a,b,c=t[:,0],t[:,1],t[:,2]; ab,bc,ca=m[0],m[1],m[2]
t=np.concatenate([np.stack(x,1) for x in [(a,ab,g),(ab,b,g),(b,bc,g),(bc,c,g),(c,ca,g),(ca,a,g)]])
write(sys.argv[2],v,t); print(len(v),len(t))
