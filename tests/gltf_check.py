"""Structural check of a binary glTF 2.0 file (.glb) against the rules of the
glTF 2.0 specification that a viewer relies on, with numpy only (no glTF
package is in Debian): the GLB header and chunks (§4.4), buffer views inside
the buffer, accessors inside their views with 4-byte alignment, byteStride
rules, POSITION min/max present and equal to the data (§3.6.2.5, morph
targets too), indices inside the vertex range, every attribute of one
primitive with the same count, application-specific attribute names starting
with '_', COLOR_0 in 0..1 and unit NORMALs.

    import gltf_check
    doc, arrays = gltf_check.load("skin_0003.glb")   # raises AssertionError
    arrays["_EPITHELIUM"]    # numpy array, one row per vertex

Run as a script it checks the files named on the command line and prints
OK per file (exit 1 on the first failure)."""
import json
import struct
import sys

import numpy as np

COMPONENTS = {5120: (np.int8, 1), 5121: (np.uint8, 1), 5122: (np.int16, 2),
              5123: (np.uint16, 2), 5125: (np.uint32, 4), 5126: (np.float32, 4)}
NCOMP = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
STANDARD = ("POSITION", "NORMAL", "TANGENT", "TEXCOORD_", "COLOR_", "JOINTS_", "WEIGHTS_")


def _chunks(data, path):
    assert len(data) >= 20, "%s: shorter than a GLB header" % path
    magic, version, length = struct.unpack_from("<III", data, 0)
    assert magic == 0x46546C67, "%s: magic is not glTF" % path
    assert version == 2, "%s: version %d" % (path, version)
    assert length == len(data), "%s: header length %d, file %d" % (path, length, len(data))
    off, chunks = 12, []
    while off < length:
        clen, ctype = struct.unpack_from("<II", data, off)
        assert clen % 4 == 0, "%s: chunk length %d not a multiple of 4" % (path, clen)
        assert off + 8 + clen <= length, "%s: chunk past the end" % path
        chunks.append((ctype, data[off + 8:off + 8 + clen]))
        off += 8 + clen
    assert off == length, "%s: trailing bytes" % path
    assert chunks and chunks[0][0] == 0x4E4F534A, "%s: first chunk is not JSON" % path
    assert len(chunks) <= 2 and all(c[0] == 0x004E4942 for c in chunks[1:]), \
        "%s: unexpected chunks" % path
    return chunks


def _accessor(doc, bins, i, path):
    a = doc["accessors"][i]
    dtype, csize = COMPONENTS[a["componentType"]]
    n = NCOMP[a["type"]]
    count = a["count"]
    assert count >= 1, "%s: accessor %d is empty" % (path, i)
    v = doc["bufferViews"][a["bufferView"]]
    buf = bins[v["buffer"]]
    voff = v.get("byteOffset", 0)
    assert voff + v["byteLength"] <= len(buf), "%s: view %d past its buffer" % (path, a["bufferView"])
    aoff = a.get("byteOffset", 0)
    assert (voff + aoff) % csize == 0, "%s: accessor %d misaligned" % (path, i)
    elem = csize * n
    stride = v.get("byteStride", elem)
    if "byteStride" in v:
        assert 4 <= stride <= 252 and stride % 4 == 0, "%s: view byteStride %d" % (path, stride)
        assert v.get("target") != 34963, "%s: an index view has a byteStride" % path
    assert stride >= elem, "%s: accessor %d: stride %d < element %d" % (path, i, stride, elem)
    assert aoff + stride * (count - 1) + elem <= v["byteLength"], \
        "%s: accessor %d runs past its view" % (path, i)
    raw = buf[voff + aoff: voff + aoff + stride * (count - 1) + elem]
    if stride == elem:
        arr = np.frombuffer(raw, dtype=dtype, count=count * n)
    else:
        arr = np.stack([np.frombuffer(raw, dtype=dtype, count=n, offset=k * stride)
                        for k in range(count)])
    arr = arr.reshape(count, n) if n > 1 else arr.reshape(count)
    return a, arr


def _minmax(a, arr, what, path):
    assert "min" in a and "max" in a, "%s: %s has no min/max" % (path, what)
    lo = np.asarray(a["min"], np.float32)
    hi = np.asarray(a["max"], np.float32)
    got_lo = arr.min(axis=0).astype(np.float32)
    got_hi = arr.max(axis=0).astype(np.float32)
    assert np.array_equal(lo, got_lo) and np.array_equal(hi, got_hi), \
        "%s: %s min/max %s %s, data %s %s" % (path, what, lo, hi, got_lo, got_hi)


def load(path):
    with open(path, "rb") as f:
        data = f.read()
    chunks = _chunks(data, path)
    doc = json.loads(chunks[0][1].decode("utf-8"))
    assert doc["asset"]["version"] == "2.0", path
    bins = []
    for k, b in enumerate(doc["buffers"]):
        assert "uri" not in b and k == 0 and len(chunks) == 2, \
            "%s: buffer %d is not the BIN chunk" % (path, k)
        blen = len(chunks[1][1])
        assert b["byteLength"] <= blen <= b["byteLength"] + 3, \
            "%s: buffer byteLength %d, BIN chunk %d" % (path, b["byteLength"], blen)
        bins.append(chunks[1][1])
    for i, v in enumerate(doc["bufferViews"]):
        assert v["byteLength"] >= 1 and v.get("byteOffset", 0) + v["byteLength"] <= \
            doc["buffers"][v["buffer"]]["byteLength"], "%s: view %d past its buffer" % (path, i)
    arrays = {}
    for m in doc["meshes"]:
        for pr in m["primitives"]:
            assert pr.get("mode", 4) == 4, "%s: not triangles" % path
            count = None
            for name, i in pr["attributes"].items():
                assert name.startswith(STANDARD) or name.startswith("_"), \
                    "%s: attribute %s is neither standard nor starts with '_'" % (path, name)
                a, arr = _accessor(doc, bins, i, path)
                assert count is None or a["count"] == count, \
                    "%s: attribute %s has %d elements, not %d" % (path, name, a["count"], count)
                count = a["count"]
                assert np.isfinite(arr).all() if arr.dtype.kind == "f" else True, \
                    "%s: %s has non-finite values" % (path, name)
                if name == "POSITION":
                    _minmax(a, arr, name, path)
                if name == "NORMAL":
                    ln = np.linalg.norm(arr, axis=1)
                    assert np.all(np.abs(ln - 1) < 5e-3), "%s: NORMAL not unit length" % path
                if name.startswith("COLOR_"):
                    assert a["type"] in ("VEC3", "VEC4") and arr.min() >= 0 and arr.max() <= 1, \
                        "%s: %s outside 0..1" % (path, name)
                arrays[name] = arr
            a, idx = _accessor(doc, bins, pr["indices"], path)
            assert a["type"] == "SCALAR" and a["count"] % 3 == 0, "%s: indices" % path
            assert int(idx.max()) < count, "%s: index %d >= %d vertices" % (path, idx.max(), count)
            arrays["indices"] = idx
            for t, tgt in enumerate(pr.get("targets", [])):
                for name, i in tgt.items():
                    assert name in pr["attributes"], "%s: target %s not in attributes" % (path, name)
                    a, arr = _accessor(doc, bins, i, path)
                    assert a["count"] == count, "%s: target %d count" % (path, t)
                    if name == "POSITION":
                        _minmax(a, arr, "target %d POSITION" % t, path)
                    arrays["target%d/%s" % (t, name)] = arr
            if "targets" in pr:
                assert len(m.get("weights", [0] * len(pr["targets"]))) == len(pr["targets"])
    return doc, arrays


if __name__ == "__main__":
    for p in sys.argv[1:]:
        try:
            load(p)
        except (AssertionError, KeyError, ValueError) as e:
            print("FAIL: %s: %s" % (p, e))
            sys.exit(1)
        print("OK: %s" % p)
