#!/usr/bin/env python3
"""Assembles the per-rank pieces of every fields_NNNN.pvti of an MPI run folder
and checks them against the single-process run's fields_NNNN.vti: every cell
array (cell_state and the eight fields) and the closed_day field array equal
byte for byte, the pieces tile the grid exactly once, and the MPI run wrote no
whole-grid .vti (tests/e2e_mpi.sh, docs/scaling.md).
usage: pvti_same.py REF_RUN MPI_RUN [last]   (last: only the newest of each)"""
import re, struct, sys, glob, os
def read(path):  # extent, {name: (itemsize, bytes)}, closed_day bytes or None
    b = open(path, 'rb').read()
    head, raw = b.split(b'<AppendedData encoding="raw">', 1)
    raw = raw[raw.index(b'_') + 1:]
    m = re.search(rb'<Piece Extent="([^"]+)"', head)
    ext = [int(v) for v in m.group(1).split()]
    arrays = {}
    for typ, name, off in re.findall(rb'<DataArray type="(\w+)" Name="(\w+)"[^>]*format="appended" offset="(\d+)"', head):
        off = int(off)
        n = struct.unpack('<Q', raw[off:off + 8])[0]
        arrays[name.decode()] = ({b'UInt8': 1, b'Float32': 4, b'Float64': 8}[typ], raw[off + 8:off + 8 + n])
    return ext, arrays
def check(whole_path, pvti_path):
    wext, whole = read(whole_path)
    NX, NY, NZ = wext[1], wext[3], wext[5]
    pv = open(pvti_path).read()
    pieces = re.findall(r'<Piece Extent="([^"]+)" Source="([^"]+)"', pv)
    asm = {k: bytearray(len(v[1])) for k, v in whole.items()}
    cells = bytearray(NX * NY * NZ)
    cols = {}
    for ext_s, src in pieces:
        ext, arrs = read(os.path.join(os.path.dirname(pvti_path), src))
        assert [int(v) for v in ext_s.split()] == ext, (ext_s, ext)
        assert set(arrs) == set(whole), (src, sorted(arrs), sorted(whole))
        x0, x1, y0, y1, z0, z1 = ext
        w = x1 - x0
        for name, (isz, a) in arrs.items():
            if name == 'closed_day':
                k = 0
                for y in range(y0, y1):
                    o = (y * NX + x0) * 8
                    seg = a[k:k + w * 8]
                    prev = cols.get((y, x0))
                    assert prev is None or prev == seg, (src, 'closed_day of a column differs between pieces')
                    cols[(y, x0)] = seg
                    asm[name][o:o + w * 8] = seg
                    k += w * 8
                continue
            k = 0
            for z in range(z0, z1):
                for y in range(y0, y1):
                    o = ((z * NY + y) * NX + x0) * isz
                    asm[name][o:o + w * isz] = a[k:k + w * isz]
                    if name == 'cell_state':
                        for x in range(w): cells[o + x] += 1
                    k += w * isz
    assert set(cells) == {1}, pvti_path + ': pieces overlap or leave gaps'
    for name, (isz, a) in whole.items():
        assert bytes(asm[name]) == a, '%s: %s differs from %s' % (pvti_path, name, whole_path)
    return len(pieces)
ref, dist = sys.argv[1], sys.argv[2]
vtis = sorted(glob.glob(ref + '/fields/fields_[0-9][0-9][0-9][0-9].vti'))
pvtis = sorted(glob.glob(dist + '/fields/fields_[0-9][0-9][0-9][0-9].pvti'))
if len(sys.argv) > 3 and sys.argv[3] == 'last':
    vtis, pvtis = vtis[-1:], pvtis[-1:]
assert len(vtis) == len(pvtis) and vtis, (len(vtis), len(pvtis))
assert not glob.glob(dist + '/fields/fields_[0-9][0-9][0-9][0-9].vti'), dist + ': a whole-grid .vti under MPI'
for v, p in zip(vtis, pvtis):
    check(v, p)
