#!/usr/bin/env python3
"""Writes the seed corpora of the fuzz targets into fuzz/seeds/TARGET/.

Sources: the small real meshes of ../shared/meshes beside the clone (copied as they are, so their own
formatting, comments and edge counts are kept), pieces of the larger ones (their first
faces, renumbered, so colours, polygons and large coordinates are represented), the
same pieces written as OBJ, PLY (ASCII, binary both byte orders) and STL (ASCII and
binary), the heads of the point clouds in ../shared/points (read_points, and the
PLY ones for read_ply_ascii), the experiment files and request bodies of
docs/experiment-files.md, the web page's request bodies (web_body), and hand-made edge
cases. Standard library only.

    python3 fuzz/make_seeds.py [--meshes DIR] [--points DIR]
    python3 fuzz/make_seeds.py --only web_body      # that target's seeds only

The output is deterministic; the seeds are committed, so CI does not run this.
"""

import argparse
import hashlib
import json
import os
import shutil
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "seeds")

SMALL = ["tetrahedron.off", "cube.off", "octahedron.off", "degtri_sliding.off",
         "3torus.off", "torus_quad.off"]
PIECES = ["double-torus-example.off", "cactus.off", "polygon_mesh.off", "fandisk.off", "blobby_3cc.off",
          "elephant-with-holes.off", "eight.off", "mesh_with_border.off"]


def put(target, name, data):
    d = os.path.join(OUT, target)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def put_each(target, cases, prefix="", head=b""):
    """put() every case of `cases`: a dict under its keys, a list as PREFIX00, PREFIX01, ...;
    `head` (a selector byte) before each."""
    if isinstance(cases, dict):
        named = cases.items()
    else:
        named = ((f"{prefix}{k:02}", t) for k, t in enumerate(cases))
    for name, t in named:
        put(target, name, head + t.encode() if head else t)


def parse_off(text):
    """Vertices (list of float triples), colours (or None) and faces of an OFF file."""
    toks = []
    for line in text.splitlines():
        line = line.split("#")[0]
        toks.append(line.split())
    flat = [(i, t) for i, ts in enumerate(toks) for t in ts]
    header = flat[0][1]
    pos = 1
    nv, nf = int(flat[pos][1]), int(flat[pos + 1][1])
    pos += 2
    if pos < len(flat) and flat[pos][0] == flat[pos - 1][0]:
        pos += 1  # edge count on the same line
    verts, colours = [], []
    for _ in range(nv):
        line = flat[pos][0]
        vals = [t for (i, t) in flat[pos:] if i == line]
        verts.append(tuple(float(x) for x in vals[:3]))
        if "C" in header and len(vals) >= 6:
            colours.append(tuple(float(x) for x in vals[3:6]))
        pos += len(vals)
    faces = []
    for _ in range(nf):
        k = int(flat[pos][1])
        faces.append([int(flat[pos + 1 + j][1]) for j in range(k)])
        line = flat[pos][0]
        pos += 1 + k
        while pos < len(flat) and flat[pos][0] == line:
            pos += 1  # face colour
    return verts, (colours if len(colours) == nv else None), faces


def piece(verts, colours, faces, nfaces):
    """The first `nfaces` faces with their vertices, renumbered."""
    faces = faces[:nfaces]
    used = sorted({v for f in faces for v in f})
    new = {v: i for i, v in enumerate(used)}
    v = [verts[i] for i in used]
    c = [colours[i] for i in used] if colours else None
    return v, c, [[new[i] for i in f] for f in faces]


def triangles(faces):
    return [[f[0], f[i], f[i + 1]] for f in faces for i in range(1, len(f) - 1)]


def fmt(x):
    return repr(float(x))


def off_text(v, c, faces):
    head = "COFF" if c else "OFF"
    out = [head, f"{len(v)} {len(faces)} 0"]
    for i, p in enumerate(v):
        s = " ".join(fmt(x) for x in p)
        if c:
            s += " " + " ".join(str(int(x)) if x > 1 else fmt(x) for x in c[i]) + " 255"
        out.append(s)
    out += [f"{len(f)} " + " ".join(map(str, f)) for f in faces]
    return "\n".join(out) + "\n"


def obj_text(v, c, faces, style):
    out = ["# piece", "o piece"]
    for i, p in enumerate(v):
        s = "v " + " ".join(fmt(x) for x in p)
        if c:
            s += " " + " ".join(fmt(x / 255 if x > 1 else x) for x in c[i])
        out.append(s)
    if style >= 1:
        out.append("vt 0.5 0.5")
        out.append("vn 0 0 1")
    n = len(v)
    for f in faces:
        if style == 0:
            corners = [str(i + 1) for i in f]
        elif style == 1:
            corners = [f"{i + 1}/1/1" for i in f]
        else:
            corners = [f"{i - n}//1" for i in f]  # negative (relative) indices
        out.append("f " + " ".join(corners))
    return "\n".join(out) + "\n"


def ply_header(fmt_name, v, c, faces, coord="double", count="uchar", index="int"):
    h = ["ply", f"format {fmt_name} 1.0", "comment seed", f"element vertex {len(v)}"]
    h += [f"property {coord} {a}" for a in "xyz"]
    if c:
        h += [f"property uchar {a}" for a in ("red", "green", "blue")]
    h += [f"element face {len(faces)}", f"property list {count} {index} vertex_indices",
          "end_header"]
    return "\n".join(h) + "\n"


def colour_bytes(c):
    return [int(x) if x > 1 else int(round(x * 255)) for x in c]


def ply_ascii(v, c, faces):
    out = ply_header("ascii", v, c, faces)
    for i, p in enumerate(v):
        s = " ".join(fmt(x) for x in p)
        if c:
            s += " " + " ".join(str(x) for x in colour_bytes(c[i]))
        out += s + "\n"
    for f in faces:
        out += f"{len(f)} " + " ".join(map(str, f)) + "\n"
    return out


SCALARS = ["float", "double", "uchar", "char", "short", "ushort", "int", "uint"]
PACK = {"float": "f", "double": "d", "uchar": "B", "char": "b", "short": "h",
        "ushort": "H", "int": "i", "uint": "I"}
COUNTS = ["uchar", "ushort", "uint", "char"]
INDICES = ["int", "uint", "short", "ushort", "uchar", "char"]


def ply_payload(v, c, faces, big, coord, count, index):
    e = ">" if big else "<"
    out = b""
    for i, p in enumerate(v):
        vals = p if coord in ("float", "double") else [int(max(-100, min(100, x))) for x in p]
        if coord in ("uchar", "ushort", "uint"):
            vals = [abs(x) for x in vals]
        out += struct.pack(e + PACK[coord] * 3, *vals)
        if c:
            out += bytes(colour_bytes(c[i]))
    for f in faces:
        out += struct.pack(e + PACK[count], len(f))
        out += struct.pack(e + PACK[index] * len(f), *f)
    return out


def ply_binary_file(v, c, faces, big):
    head = ply_header("binary_big_endian" if big else "binary_little_endian", v, c, faces)
    return head.encode() + ply_payload(v, c, faces, big, "double", "uchar", "int")


def stl_ascii(v, tris):
    out = ["solid piece"]
    for t in tris:
        out.append("  facet normal 0 0 0")
        out.append("    outer loop")
        for i in t:
            out.append("      vertex " + " ".join(fmt(x) for x in v[i]))
        out.append("    endloop")
        out.append("  endfacet")
    out.append("endsolid piece")
    return "\n".join(out) + "\n"


def stl_records(v, tris):
    out = b""
    for t in tris:
        out += struct.pack("<3f", 0, 0, 0)
        for i in t:
            out += struct.pack("<3f", *v[i])
        out += b"\0\0"
    return out


def stl_binary(v, tris):
    return b"\0" * 80 + struct.pack("<I", len(tris)) + stl_records(v, tris)


def meshes(mesh_dir):
    """(name, vertices, colours, faces) of the small meshes and of the pieces."""
    out = []
    for name in SMALL:
        path = os.path.join(mesh_dir, name)
        if os.path.exists(path):
            v, c, f = parse_off(open(path).read())
            out.append((name[:-4], v, c, f, path))
    for name in PIECES:
        path = os.path.join(mesh_dir, name)
        if os.path.exists(path):
            v, c, f = parse_off(open(path).read())
            v, c, f = piece(v, c, f, 24)
            out.append((name[:-4] + "-piece", v, c, f, None))
    return out


def hand_made_meshes():
    off = {
        "no-header": "3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
        "counts-split": "OFF\n# c\n3\n1\n0\n0 0 0 1 0 0 0 1 0\n3 0 1 2\n",
        "quad-nonplanar": "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 1\n0 1 0\n4 0 1 2 3\n",
        "nan": "OFF\n3 1 0\n0 0 nan\n1 0 0\n0 1 0\n3 0 1 2\n",
        "huge": "OFF\n3 1 0\n1e300 0 0\n0 1e300 0\n0 0 -1e300\n3 0 1 2\n",
        "index-range": "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
        "big-count": "OFF\n99999999999 1 0\n0 0 0\n",
        "repeated": "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 1\n",
        "stcnoff": "STCNOFF\n3 1 0\n0 0 0 0 0 1 0.1 0.2 0.3 1 0 0\n1 0 0 0 0 1 0.1 0.2 0.3 1 1 0\n"
                   "0 1 0 0 0 1 0.1 0.2 0.3 1 0 1\n3 0 1 2 255 0 0\n",
        "binary": "OFF BINARY\n3 1 0\n",
        "4off": "4OFF\n3 1 0\n0 0 0 1\n1 0 0 1\n0 1 0 1\n3 0 1 2\n",
        "polygon-64": "OFF\n70 1 0\n" + "".join(
            f"{__import__('math').cos(i / 70 * 6.283)} {__import__('math').sin(i / 70 * 6.283)} 0\n"
            for i in range(70)) + "70 " + " ".join(map(str, range(70))) + "\n",
    }
    obj = {
        "continuation": "v 0 0 0\nv 1 0 \\\n0\nv 0 1 0\nf 1 2 \\\n3\n",
        "relative": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n",
        "zero-index": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
        "weights": "v 0 0 0 1\nv 1 0 0 1\nv 0 1 0 1\nf 1 2 3\nl 1 2\np 3\n",
        "colours": "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 255\nf 1 2 3\n",
        "crlf": "v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1/1 2/2 3/3\r\n",
        "bad-corner": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/x 2 3\n",
        "unknown": "mtllib a.mtl\nusemtl m\ncstype bspline\nfoo bar\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    }
    ply = {
        "point-cloud": "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                       "property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n",
        "vertex-index": "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                        "property float z\nelement face 1\nproperty list uchar uint vertex_index\n"
                        "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
        "float-colours": "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                         "property double z\nproperty float red\nproperty float green\nproperty float blue\n"
                         "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                         "0 0 0 1 0 0\n1 0 0 0 1 0\n0 1 0 0 0 1\n3 0 1 2\n",
        "huge-count": "ply\nformat ascii 1.0\nelement vertex 4294967295\nproperty float x\n"
                      "property float y\nproperty float z\nelement face 1\n"
                      "property list uchar int vertex_indices\nend_header\n0 0 0\n",
        "types": "ply\nformat ascii 1.0\ncomment c\nobj_info o\nelement vertex 3\nproperty int8 x\n"
                 "property uint16 y\nproperty float64 z\nelement face 1\n"
                 "property list uint8 int32 vertex_indices\nelement edge 0\nproperty int a\n"
                 "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    }
    stl = {
        "welded": "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                  "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex -0 0 0\nvertex 0 1 0\n"
                  "vertex -1 0 0\nendloop\nendfacet\nendsolid t\n",
        "collapsed": "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0 0 0\nvertex 0 1 0\n"
                     "endloop\nendfacet\nendsolid t\n",
        "nan": "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 nan\nvertex 1 0 0\nvertex 0 1 0\n"
               "endloop\nendfacet\nendsolid t\n",
        "no-space": "solidx\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                    "vertex 0 1 0\nendloop\nendfacet\nendsolid\n",
    }
    return off, obj, ply, stl


def arbitrary_mesh_bytes(switches, scale, verts, tris):
    """Input of `arbitrary_mesh` (crates/spectral-mesh-fuzz/src/lib.rs): i8 scale exponent, u8 vertex count,
    i8 triples, u8 triples; `validate_repair` reads a switch byte first."""
    b = bytes([switches]) if switches is not None else b""
    b += struct.pack("<bB", scale, len(verts))
    for p in verts:
        b += struct.pack("<3b", *p)
    for t in tris:
        b += bytes(t)
    return b


def npy(values, code, shape, fortran=False):
    """An .npy file (format 1.0) as numpy.save writes it."""
    descr = {"d": "<f8", "q": "<i8", "B": "|u1"}[code]
    dims = "".join(f"{d}, " for d in shape).rstrip(" ") if len(shape) != 1 else f"{shape[0]},"
    header = f"{{'descr': '{descr}', 'fortran_order': {fortran}, 'shape': ({dims}), }}"
    pad = 64 - (10 + len(header) + 1) % 64
    header = header + " " * (pad % 64) + "\n"
    return (b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode()
            + struct.pack("<" + code * len(values), *values))


def basis_members(n, k, laplacian="fem", fortran=True):
    """The arrays of spectral::store::save_npz for a made-up n x k basis."""
    import json
    values = [0.0] + [float(i) * 1.5 for i in range(1, k)]
    vecs = [((i + 1) * (j + 2)) % 7 / 7.0 for j in range(k) for i in range(n)]
    meta = json.dumps({"format_version": 1, "laplacian": laplacian, "n": n, "k": k,
                       "mesh_hash": "", "params": {"k": k, "tolerance": 1e-10, "dirichlet": None,
                                                   "method": "auto", "seed": 24301,
                                                   "block_size": 0},
                       "generator": "seed"}).encode()
    return [npy(values, "d", (k,)),
            npy(vecs, "d", (n, k), fortran),
            npy([0.25] * n, "d", (n,)),
            npy(list(range(n)), "q", (n,)),
            npy(list(range(n + 1)), "q", (n + 1,)),
            npy([n, n], "q", (2,)),
            npy([1e-12] * k, "d", (k,)),
            npy(list(meta), "B", (len(meta),))]


# web_body: requests to the web server's router (see fuzz_targets/web_body.rs): a
# selector byte (bits 0-2 endpoint: 0 field, 1 download POST, 2 download GET, 3 basis,
# 4 shape, 5 cancel + status; bits 3-4 mesh: 0 sphere, 1 disk, 2 last loaded, 3 unknown;
# bits 5-6 the GET's format: none, txt, png, toml; bit 7 no Content-Length), the body,
# and up to 4 such requests separated by "\n---\n". The bodies are the page's
# (static/app.js: fieldRequest, ensureBasis, downloadUrl, the shape box) and the API
# tests' (tests/web_api.rs), good and bad.
WEB_FIELD, WEB_DL_POST, WEB_DL_GET, WEB_BASIS, WEB_SHAPE, WEB_CANCEL = 0, 1, 2, 3, 4, 5
WEB_SPHERE, WEB_DISK, WEB_LAST, WEB_UNKNOWN = 0x00, 0x08, 0x10, 0x18
WEB_TXT, WEB_PNG, WEB_TOML, WEB_NO_LENGTH = 0x20, 0x40, 0x60, 0x80


def web_part(sel, body):
    if not isinstance(body, str):
        body = json.dumps(body)
    return bytes([sel]) + body.encode()


def web_body_seeds():
    page = {"laplacian": "fem", "normalize": True, "levels": 0}
    fields = {
        "harmonic-preset": {"kind": "harmonic", "constraints": 2, **page},
        "harmonic-clicked": {"kind": "harmonic", "constraints": [{"vertex": 3, "value": 0},
                                                                  {"vertex": 90, "value": 1}], **page},
        "harmonic-order2": {"kind": "harmonic", "order": 2, "constraints": 4, **page},
        "heat": {"kind": "heat", "t": 0.5, "k": 100, **page},
        "heat-anchor": {"kind": "heat", "t": 0.002, "k": 30, "anchor": 7, **page},
        "heat-standard": {"kind": "heat", "t": 0.01, "k": 50, "kernel": "standard"},
        "diffusion-wfem": {"kind": "distance", "distance": "wfem-diffusion:t=0.5", "k": 100, "source": 5, **page},
        "distance-biharmonic": {"kind": "distance", "distance": "biharmonic", "k": 100, **page},
        "distance-commute": {"kind": "distance", "distance": "commute", "k": 100, "source": 11, **page},
        "distance-diffusion": {"kind": "distance", "distance": "diffusion:t=0.1", "k": 100, **page},
        "distance-mix": {"kind": "distance", "distance": "mix:a=0.3,t=0.1", "k": 40, "source": 3, **page},
        "distance-custom": {"kind": "distance", "distance": "custom-w:exp(-t*s);t=0.5,a=0.5", "k": 100, **page},
        "distance-custom-phi": {"kind": "distance", "distance": "custom-phi:s^2;t=0.5,a=0.5", "k": 60, **page},
        "signature": {"kind": "spectral-function", "filter": "biharmonic", "k": 100, **page},
        "segmentation-hks": {"kind": "segmentation", "signature": "hks:t=0.5", "persistence": 0.05, "k": 100, **page},
        "segmentation-filter": {"kind": "segmentation", "signature": "spectral-function:biharmonic",
                                "persistence": 0.05, "k": 100, **page},
        "embedding": {"kind": "embedding", "filter": "commute", "component": 2, "k": 100, **page},
        "eigenfunction": {"kind": "eigenfunction", "index": 3, "k": 100, **page},
        "diffusion-ball": {"kind": "diffusion", "signal": {"ball": {"vertex": 3, "radius": 0.3}}, "t": 0.01, "k": 40},
        "diffusion-impulse": {"kind": "diffusion", "signal": {"impulse": 17}},
        "hks": {"kind": "hks", "t": 0.01, "k": 40, "scaled": True},
        "wks": {"kind": "wks", "energy": 4.0, "k": 40},
        "adf": {"kind": "adf", "k": 40},
        "green": {"kind": "green", "k": 40, "levels": 7},
        "defaults": {"kind": "distance"},
    }
    for name, body in fields.items():
        put("web_body", f"field-{name}", web_part(WEB_FIELD | WEB_SPHERE, body))
    for name in ["harmonic-preset", "heat", "diffusion-wfem", "segmentation-hks", "eigenfunction"]:
        body = dict(fields[name], k=127) if "k" in fields[name] else fields[name]
        put("web_body", f"field-disk-{name}", web_part(WEB_FIELD | WEB_DISK, body))
    # Downloads: the page's links (GET, format in the query, levels and colormap in the body).
    dl = {"kind": "distance", "distance": "biharmonic", "k": 100, "laplacian": "fem",
          "normalize": True, "levels": 10, "colormap": "viridis"}
    put("web_body", "download-get-txt", web_part(WEB_DL_GET | WEB_TXT, dl))
    put("web_body", "download-get-png", web_part(WEB_DL_GET | WEB_PNG, dict(dl, size=96)))
    put("web_body", "download-get-toml", web_part(WEB_DL_GET | WEB_TOML, dict(dl, k=40)))
    put("web_body", "download-get-wrl", web_part(WEB_DL_GET, dict(dl, format="wrl")))
    put("web_body", "download-get-ply", web_part(WEB_DL_GET | WEB_DISK, dict(dl, format="ply", k=127)))
    put("web_body", "download-post-png", web_part(WEB_DL_POST, {
        "kind": "heat", "k": 30, "t": 0.05, "format": "png", "size": 64, "view": "iso",
        "colormap": "turbo", "transparent": True, "critical_points": True, "colorbar": True}))
    put("web_body", "download-post-segmentation", web_part(WEB_DL_POST, {
        "kind": "segmentation", "k": 20, "format": "png", "size": 32, "view": "30,45"}))
    put("web_body", "download-post-toml-harmonic", web_part(WEB_DL_POST, {
        "kind": "harmonic", "order": 2, "format": "toml", "colormap": "grey"}))
    # Bases: the page's (ensureBasis), other discretizations, the defaults.
    for name, sel, body in [
        ("page", WEB_SPHERE, {"laplacian": "fem", "normalize": True, "k": 100}),
        ("held", WEB_DISK, {"k": 127}),
        ("defaults", WEB_SPHERE, ""),
        ("voronoi-cot", WEB_SPHERE, {"laplacian": "voronoi-cot", "k": 20}),
        ("cot", WEB_DISK, {"laplacian": "cot", "k": 10, "normalize": False}),
        ("robust", WEB_SPHERE, {"laplacian": "robust", "k": 12}),
        ("uniform", WEB_DISK, {"laplacian": "uniform", "k": 30}),
        ("mixed-voronoi", WEB_SPHERE, {"laplacian": "mixed-voronoi", "k": 8}),
        ("more", WEB_SPHERE, {"k": 150}),
    ]:
        put("web_body", f"basis-{name}", web_part(WEB_BASIS | sel, body))
    # Sequences: a basis then its field; a shape, its basis, a field and a download; a
    # cancel and status.
    sep = b"\n---\n"
    put("web_body", "seq-basis-then-field", sep.join([
        web_part(WEB_BASIS, {"laplacian": "voronoi-cot", "k": 20}),
        web_part(WEB_FIELD, {"kind": "heat", "k": 20, "t": 0.05, "laplacian": "voronoi-cot"}),
        web_part(WEB_DL_POST, {"kind": "distance", "k": 20, "laplacian": "voronoi-cot", "format": "toml"}),
    ]))
    put("web_body", "seq-shape-basis-field", sep.join([
        web_part(WEB_SHAPE, {"shape": "sphere:res=1"}),
        web_part(WEB_BASIS | WEB_LAST, {"k": 10}),
        web_part(WEB_FIELD | WEB_LAST, {"kind": "distance", "k": 10, "source": 4}),
        web_part(WEB_DL_GET | WEB_LAST | WEB_TOML, {"kind": "heat", "k": 8}),
    ]))
    put("web_body", "seq-shape-harmonic", sep.join([
        web_part(WEB_SHAPE, {"shape": "torus:res=0"}),
        web_part(WEB_FIELD | WEB_LAST, {"kind": "harmonic", "constraints": 6, "levels": 20}),
    ]))
    put("web_body", "seq-shape-iterative-basis", sep.join([
        web_part(WEB_SHAPE, {"shape": "irregular-sphere:res=1"}),
        web_part(WEB_BASIS | WEB_LAST, {"k": 40, "laplacian": "cot"}),
        web_part(WEB_FIELD | WEB_LAST, {"kind": "hks", "k": 40, "laplacian": "cot"}),
    ]))
    put("web_body", "seq-basis-cancel", sep.join([
        web_part(WEB_BASIS | WEB_DISK, {"laplacian": "robust", "k": 50}),
        web_part(WEB_CANCEL | WEB_DISK, ""),
    ]))
    put("web_body", "cancel-idle", web_part(WEB_CANCEL, ""))
    for name, shape in [("sphere", "sphere:res=1"), ("disk", "disk:res=0"), ("cylinder", "cylinder:res=0,h=2"),
                        ("too-big", "sphere:res=9"), ("unknown", "klein-bottle-9"), ("path", "/etc/passwd")]:
        put("web_body", f"shape-{name}", web_part(WEB_SHAPE, {"shape": shape}))
    # Refusals (tests/web_api.rs, bad_input_is_a_4xx_with_a_message...).
    bad = {
        "kind-unknown": {"kind": "astrology"},
        "no-kind": {"experiment": "heat", "k": 20},
        "key-of-another-kind": {"kind": "heat", "k": 20, "filter": "commute"},
        "levels": {"kind": "heat", "k": 20, "levels": 100000},
        "t-negative": {"kind": "heat", "k": 20, "t": -1.0},
        "anchor-out-of-range": {"kind": "heat", "k": 20, "anchor": 162},
        "constraint-out-of-range": {"kind": "harmonic", "constraints": [{"vertex": 0, "value": 0},
                                                                          {"vertex": 99999, "value": 1}]},
        "k-too-many": {"kind": "heat", "k": 167},
        "k-more-than-held": {"kind": "heat", "k": 120},
        "k-zero": {"kind": "hks", "k": 0},
        "index-k1": {"kind": "eigenfunction", "k": 1},
        "filter-syntax": {"kind": "distance", "k": 20, "distance": "custom-w:exp(-t*;t=1"},
        "filter-negative": {"kind": "distance", "k": 20, "distance": "custom-w:s-1000"},
        "laplacian": {"kind": "heat", "laplacian": "nope"},
        "not-held-laplacian": {"kind": "heat", "k": 10, "laplacian": "robust"},
        "normalize": {"kind": "heat", "normalize": "yes"},
        "not-an-object": [1, 2],
        "syntax": '{"kind": "heat", ',
    }
    for name, body in bad.items():
        put("web_body", f"bad-field-{name}", web_part(WEB_FIELD, body))
    put("web_body", "bad-download-format", web_part(WEB_DL_POST, {"kind": "heat", "k": 20, "format": "exe"}))
    put("web_body", "bad-download-size", web_part(WEB_DL_POST, {"kind": "heat", "k": 20, "format": "png", "size": 100000}))
    put("web_body", "bad-download-size-budget", web_part(WEB_DL_GET | WEB_PNG, {"kind": "heat", "size": 4096}))
    put("web_body", "bad-download-colormap", web_part(WEB_DL_GET | WEB_PNG, {"kind": "heat", "colormap": "jet"}))
    put("web_body", "bad-download-query", web_part(WEB_DL_GET | WEB_TXT, "kind=heat"))
    put("web_body", "bad-basis-key", web_part(WEB_BASIS, {"pairs": 5}))
    put("web_body", "bad-basis-laplacian", web_part(WEB_BASIS, {"laplacian": "nope", "k": 5}))
    put("web_body", "bad-basis-k", web_part(WEB_BASIS | WEB_DISK, {"k": 128}))
    put("web_body", "bad-basis-k-zero", web_part(WEB_BASIS, {"k": 0}))
    put("web_body", "bad-unknown-mesh", web_part(WEB_FIELD | WEB_UNKNOWN, {"kind": "heat"}))
    put("web_body", "bad-no-length", web_part(WEB_FIELD | WEB_NO_LENGTH, {"kind": "heat", "k": 20}))
    put("web_body", "bad-empty", bytes([WEB_FIELD]))


def main():
    ap = argparse.ArgumentParser()
    # The shared folder beside the clone (../shared next to the repository's root).
    shared = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared")
    ap.add_argument("--meshes", default=os.path.join(shared, "meshes"))
    ap.add_argument("--points", default=os.path.join(shared, "points"))
    ap.add_argument("--only", choices=["web_body"],
                    help="rewrite the seeds of this target only")
    args = ap.parse_args()
    if args.only == "web_body":
        shutil.rmtree(os.path.join(OUT, "web_body"), ignore_errors=True)
        web_body_seeds()
        return
    if os.path.isdir(OUT):
        shutil.rmtree(OUT)
    ms = meshes(args.meshes)
    for name, v, c, faces, path in ms:
        tris = triangles(faces)
        off = open(path).read() if path else off_text(v, c, faces)
        put("read_off", name + ".off", off)
        put("pipeline_eigen", name + ".off", b"\x02" + off.encode())
        put("read_obj", name + ".obj", obj_text(v, c, faces, len(name) % 3))
        put("read_ply_ascii", name + ".ply", ply_ascii(v, c, faces))
        put("read_ply_ascii", name + "-le.ply", ply_binary_file(v, c, faces, False))
        put("read_stl_ascii", name + ".stl", stl_ascii(v, tris))
        put("read_stl_binary", name + ".bin", b"\x00" + stl_records(v, tris))
        put("read_stl_binary", name + "-raw.bin", b"\x80" + stl_binary(v, tris))
        # Structured binary PLY: 4 selector bytes, then the payload (see read_ply_binary.rs).
        if len(v) < 256 and len(faces) < 256:
            for h0, coord, count, index in [(0, "double", "uchar", "int"),
                                            (1, "float", "uint", "uint"),
                                            (2 if c else 0, "double", "ushort", "short"),
                                            (8, "int", "uchar", "uchar"),
                                            (5, "short", "char", "ushort")]:
                cc = c if h0 & 2 else None
                if index in ("uchar", "char", "short") and len(v) > 127:
                    continue
                h1 = SCALARS.index(coord) | COUNTS.index(count) << 3 | INDICES.index(index) << 5
                payload = ply_payload(v, cc, faces, bool(h0 & 1), coord, count, index)
                if h0 & 4:
                    payload += struct.pack(">ii", 0, 1)
                put("read_ply_binary", f"{name}-{h0}-{coord}.bin",
                    bytes([h0, h1, len(v), len(faces)]) + payload)
        put("read_ply_binary", name + "-raw.bin", b"\x80" + ply_binary_file(v, c, faces, False))
        for k, (ext, data) in enumerate([(2, off), (4, obj_text(v, c, faces, 0)),
                                         (6, ply_ascii(v, c, faces)), (7, stl_ascii(v, tris)),
                                         (1, stl_binary(v, tris)), (1, off), (9, ply_ascii(v, c, faces))]):
            data = data.encode() if isinstance(data, str) else data
            put("detect_format", f"{name}-{k}", bytes([ext]) + data)
    # Raw whole-file binary PLY seeds for read_ply_binary's 0x80 mode.
    for name, v, c, faces, _ in ms[:4]:
        put("read_ply_binary", name + "-raw-be.bin", b"\x80" + ply_binary_file(v, c, faces, True))
    off, obj, ply, stl = hand_made_meshes()
    for k, t in off.items():
        put("read_off", k + ".off", t)
        put("detect_format", "off-" + k, b"\x01" + t.encode())
    for k, t in obj.items():
        put("read_obj", k + ".obj", t)
        put("detect_format", "obj-" + k, b"\x00" + t.encode())
    for k, t in ply.items():
        put("read_ply_ascii", k + ".ply", t)
    for k, t in stl.items():
        put("read_stl_ascii", k + ".stl", t)
    # Point clouds: the first lines of each file, behind read_points' name byte (0 = p.xyz,
    # 1 = p.pts, 4 = p.ply, 6 = no extension; see fuzz_targets/read_points.rs). A PLY point
    # cloud is refused as a mesh: also a read_ply_ascii seed.
    if os.path.isdir(args.points):
        for name in sorted(os.listdir(args.points)):
            path = os.path.join(args.points, name)
            if name.endswith(".xyz"):
                head = b"".join(open(path, "rb").readlines()[:40])
                put("read_points", name, b"\x00" + head)
                put("read_points", name + "-noext", b"\x06" + head)
            elif name.endswith(".ply"):
                raw = open(path, "rb").read()
                end = raw.index(b"end_header\n") + len(b"end_header\n")
                header = raw[:end].decode()
                props = [l for l in header.splitlines() if l.startswith("property")]
                size = sum(8 if "double" in l else 4 for l in props)
                lines = [("element vertex 40" if l.startswith("element vertex") else l)
                         for l in header.splitlines()]
                head = ("\n".join(lines) + "\n").encode() + raw[end:end + 40 * size]
                put("read_points", name, b"\x04" + head)
                put("read_ply_ascii", "points-" + name, head)
    hand_points = {
        "pts-count": (1, "3\n0 0 0\n1 0 0\n0 1 0\n"),
        "pts-count-wrong": (1, "4\n0 0 0\n1 0 0\n"),
        "header-normals": (0, "x y z nx ny nz\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 0\n"),
        "zero-normals": (0, "0 0 0 0 0 0\n1 0 0 0 0 0\n"),
        "csv": (3, "# comment\n0,0,0\n1;2;3\n4\t5\t6  # end\r\n"),
        "ragged": (2, "0 0 0\n1 2 3 4 5 6\n"),
        "four-values": (2, "0 0 0 1\n"),
        "nan": (0, "0 0 nan\n"),
        "inf-normal": (0, "0 0 0 0 0 inf\n"),
        "extremes": (0, "1.7976931348623157e308 -5e-324 -0\n"),
        "not-utf8": (0, b"0 0 0\n\xff\xfe 1 2\n"),
        "empty": (0, ""),
        "comments-only": (0, "# nothing\n\n"),
        "ply-vertex-only": (4, "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                               "property float y\nproperty float z\nend_header\n0 0 0\n1 1 1\n"),
        "ply-zero-faces": (6, "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\n"
                              "property double y\nproperty double z\nproperty double nx\n"
                              "property double ny\nproperty double nz\nelement face 0\n"
                              "property list uchar int vertex_indices\nend_header\n1 2 3 0 0 1\n"),
        "ply-with-face": (4, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                             "property float y\nproperty float z\nelement face 1\n"
                             "property list uchar int vertex_indices\nend_header\n"
                             "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
        "off-as-points-name": (0, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
        "points-as-off-name": (8, "0 0 0\n1 0 0\n0 1 0\n"),
    }
    for k, (b, t) in hand_points.items():
        t = t.encode() if isinstance(t, str) else t
        put("read_points", k, bytes([b]) + t)
    # pipeline_points: pick byte (neighbours 2 + low 4 bits, 0x10 normals from the cloud,
    # union = bits 5-6), then point_cloud_bytes.
    def point_cloud_bytes(pick, scale, pts, normals=None):
        b = struct.pack("<BbBB", pick, scale, (len(pts) - 1) % 64, 1 if normals else 0)
        for i, p in enumerate(pts):
            b += struct.pack("<3b", *p)
            if normals:
                b += struct.pack("<3b", *normals[i])
        return b
    import math
    sphere = []
    for i in range(40):
        z = 1 - 2 * (i + 0.5) / 40
        r = math.sqrt(1 - z * z)
        a = i * math.pi * (3 - math.sqrt(5))
        sphere.append((round(100 * r * math.cos(a)), round(100 * r * math.sin(a)), round(100 * z)))
    octa = [(9, 0, 0), (-9, 0, 0), (0, 9, 0), (0, -9, 0), (0, 0, 9), (0, 0, -9)]
    cube = [(x, y, z) for x in (0, 9) for y in (0, 9) for z in (0, 9)]
    grid = [(x, y, 0) for x in range(4) for y in range(4)]
    clouds = {
        "sphere": (0x0c, 0, sphere, None),
        "sphere-normals": (0x1c, 30, sphere, sphere),
        "sphere-multiplicity": (0x4c, 0, sphere, None),
        "sphere-interleaved": (0x6c, -30, sphere, None),
        "octahedron": (0x04, 0, octa, None),
        "cube-consensus-only": (0x26, 0, cube, None),
        "grid-coplanar": (0x06, 1, grid, None),
        "line": (0x02, 0, [(i, i, i) for i in range(6)], None),
        "coincident": (0x03, 0, [(1, 1, 1)] * 5, None),
        "two-points": (0x00, 0, [(0, 0, 0), (1, 0, 0)], None),
        "one-point": (0x00, 0, [(0, 0, 0)], None),
        "duplicates": (0x08, 0, octa + octa[:3], None),
        "zero-normals": (0x14, 0, octa, [(0, 0, 0)] * 6),
        "huge-scale": (0x08, 100, sphere[:20], None),
        "tiny-scale": (0x08, -100, sphere[:20], None),
    }
    for k, (pick, scale, pts, nr) in clouds.items():
        put("pipeline_points", k, point_cloud_bytes(pick, scale, pts, nr))
    # Hand-made meshes for validate_repair and pipeline_eigen (see arbitrary_mesh).
    tet = [(0, 0, 0), (9, 0, 0), (0, 9, 0), (0, 0, 9)]
    tet_t = [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)]
    bowtie = [(0, 0, 0), (5, 0, 0), (0, 5, 0), (-5, 0, 0), (0, -5, 0)]
    cases = {
        "tetra": (tet, tet_t),
        "tetra-dup-flip": (tet, tet_t + [(0, 1, 2), (3, 1, 0)]),
        "bowtie": (bowtie, [(0, 1, 2), (0, 3, 4)]),
        "fin": (tet + [(5, 5, 5)], tet_t + [(0, 1, 4)]),
        "collinear": ([(0, 0, 0), (1, 1, 1), (2, 2, 2), (0, 1, 0)], [(0, 1, 2), (0, 1, 3)]),
        "unreferenced": (tet + [(1, 2, 3), (4, 4, 4)], tet_t[:3]),
    }
    for k, (v, t) in cases.items():
        for sw, scale in [(31, 0), (5, -100), (26, 100), (0, 1)]:
            put("validate_repair", f"{k}-{sw}-{scale}", arbitrary_mesh_bytes(sw, scale, v, t))
        for b in (0x80, 0x82, 0xC4):
            put("pipeline_eigen", f"{k}-{b:x}", bytes([b]) + arbitrary_mesh_bytes(None, 0, v, t))
    constraints = {
        "basic": "0 0\n3 1\n",
        "comments": "# vertex value\n0, 0.5  # first\n\n12\t-1e-3\r\n",
        "conflict": "1 0\n1 1\n",
        "same-twice": "1 0\n1 0\n",
        "unreferenced": "4 1\n",
        "range": "18446744073709551615 1\n",
        "overflow": "18446744073709551616 1\n",
        "nan": "0 nan\n",
        "inf": "0 1e400\n",
        "three": "0 1 2\n",
        "one": "7\n",
        "negative": "-1 0\n",
        "unicode": "0\u00a01\n",
    }
    put_each("constraints", constraints)
    filters = ["diffusion:t=0.5", "heat", "heat:t=1e-300", "commute", "commute-time",
               "biharmonic", "bi-harmonic", "mix:a=0.3,t=0.7", "mix", "poly:p=2",
               "polynomial:p=-1", "band:1,4,5", "band-suppression:0", "band:",
               "custom-w:exp(-s*t)/s;t=0.1", "custom-phi:s^2", "custom-w:1/(s-1)",
               "custom-w:max(s,1);a=1,b=2", "custom-phi:sin(s)+2", "diffusion:t=-1",
               "mix:a=2", "poly:p=nan", "custom-w:s;t=inf", "custom-w:pow(s,-t)^2;t=3"]
    put_each("filter", filters, "f")
    exprs = ["1 + 2 * 3", "-s^2", "2^3^2", "(1+2)*3", "2*-s", "exp(-s*t)/s",
             "max(s, 1) + min(s, 1) + pow(2, 3)", "1e-3 * 1E3", "sqrt(abs(-4)) + log(exp(1))",
             "tanh(0) + sin(0) + cos(pi)", "a*s + t", "ln(s)", "1.", ".5e+3", "((s))",
             "- - s", "s ^ -a", "1e400", "(" * 30 + "s" + ")" * 30, "-" * 40 + "s",
             "s+" * 40 + "s"]
    put_each("filter_expr", exprs, "e")
    shapes = ["3torus", "3torus:res=0", "torus:res=1,R=2,r=0.5", "sphere:res=2",
              "uv-sphere:res=0", "double-torus:res=0", "disk:res=1", "cylinder:res=0,r=1,h=3",
              "irregular-sphere:res=2", "irregular-torus:res=1", "sphere:res=1,irregular=1",
              "icosphere", "disc", "tube:h=0.1", "2torus", "triple-torus:res=0",
              "IRREGULAR-DISK:res=0", "torus:r=2,R=1", "sphere:res=99", "torus:res=8",
              "sphere:res=1,res=2", "cylinder:h=-1", "torus:R=1e300,r=1e-300,res=0",
              "sphere:foo=1", "sphere:", ":", "sphere:res=1,,"]
    put_each("shape", shapes, "s")
    fields = {
        "basic": "1\n2.5\n-3e-7\n",
        "numpy-savetxt": "1.000000000000000000e+00\n-2.500000000000000000e-01\n",
        "comments": "# header\n0.1  # c\n\n\t-0.0\r\n",
        "extremes": "5e-324\n1.7976931348623157e308\n-2.2250738585072014e-308\n",
        "two-per-line": "1 2\n",
        "nan": "1\nnan\n",
        "inf": "inf\n",
        "overflow": "1e309\n",
        "text": "x\n",
        "comma": "1,2\n",
        "plus": "+1\n+.5\n",
    }
    put_each("field_text", fields)
    perturbs = ["noise:0.1", "noise:0.1,seed=3", "scale:2", "localscale:0,0,0,0.5,2",
                "localscale:v=3,0.5,2", "rotate:axis=x,angle=30", "rotate:45",
                "rotate:axis=1/1/0,angle=10,t=1/2/3", "translate:1,2,3", "resample:2",
                "resample:1.5,seed=2,mode=irregular", "refine:0,0,0,0.3,2", "refine:v=0,0.3,1",
                "hole:0,0,0,0.2", "hole:v=1,0.2", "tiny:3", "missing:2,seed=1", "bend:30",
                "bend:30,axis=y", "noise:nan", "scale:1e400", "resample:1e9", "noise:,"]
    put_each("perturb_spec", perturbs, "p")
    import io
    import zipfile
    names = ["eigenvalues", "eigenvectors", "mass_data", "mass_indices", "mass_indptr",
             "mass_shape", "residuals", "meta"]
    for n, k, lap, fortran in [(4, 2, "fem", True), (6, 3, "cot", False), (3, 1, "uniform", True)]:
        members = basis_members(n, k, lap, fortran)
        put("basis_npz", f"basis-{n}x{k}", b"NPYSEP".join(members))
        raw = io.BytesIO()
        with zipfile.ZipFile(raw, "w", zipfile.ZIP_DEFLATED) as z:
            for name, m in zip(names, members):
                z.writestr(name + ".npy", m)
        put("basis_npz", f"basis-{n}x{k}-zip", b"\x80" + raw.getvalue())
    members = basis_members(4, 2)
    members[1] = npy([0.0] * 8, "d", (4, 2 ** 62))  # a shape far beyond the data
    put("basis_npz", "huge-shape", b"NPYSEP".join(members))
    members = basis_members(4, 2)
    members[5] = npy([2 ** 62, 2 ** 62], "q", (2,))
    put("basis_npz", "huge-mass-shape", b"NPYSEP".join(members))
    # Field requests: byte 0 (even) = JSON, 1 (odd) = TOML.
    requests_json = [
        '{"kind": "distance"}',
        '{"kind": "distance", "source": 3, "distance": "diffusion:t=0.1", "k": 20}',
        '{"kind": "distance", "distance": "wfem-diffusion:t=0.5"}',
        '{"kind": "heat", "anchor": 40, "t": 0.05, "kernel": "voronoi-cot", "k": 20}',
        '{"kind": "diffusion", "signal": {"values": [0, 1, 0.5]}, "t": 1e-3}',
        '{"kind": "diffusion", "signal": {"ball": {"vertex": 2, "radius": 0.25}}}',
        '{"kind": "diffusion", "signal": {"impulse": 7}, "kernel": "standard"}',
        '{"kind": "harmonic", "constraints": 4, "order": 2}',
        '{"kind": "harmonic", "constraints": [{"vertex": 0, "value": 0}, {"vertex": 5, "value": 1.5}]}',
        '{"kind": "spectral-function", "filter": "custom-w:exp(-s*t)/s;t=0.1"}',
        '{"kind": "hks", "t": 0.1, "scaled": true}',
        '{"kind": "wks", "energy": 2.5, "sigma": 0.5}',
        '{"kind": "adf", "t": 0.2, "k": 30}',
        '{"kind": "segmentation", "signature": "wks:e=1,sigma=0.5", "persistence": 0.1}',
        '{"kind": "segmentation", "signature": [0.5, 1, 2]}',
        '{"kind": "segmentation", "signature": "spectral-function:mix:a=0.3,t=0.7"}',
        '{"kind": "embedding", "filter": "commute", "component": 2, "k": 50}',
        '{"kind": "eigenfunction", "index": 3, "k": 10}',
        '{"kind": "green", "source": 1, "filter": "biharmonic"}',
        '{"kind": "heat", "anchor": 18446744073709551615}',
        '{"kind": "heat", "t": 1e308, "k": 0}',
        '{"kind": "heat", "extra": 1}',
        '{"kind": "eigenfunction", "index": 10, "k": 10}',
    ]
    put_each("field_request", requests_json, "json-", b"\x00")
    requests_toml = [
        'kind = "heat"\nanchor = 40\nt = 0.05\nkernel = "wfem"\nk = 20\n',
        'kind = "harmonic"\nconstraints = [{ vertex = 12, value = 0.0 }, { vertex = 873, value = 1.0 }]\n',
        'kind = "diffusion"\nt = 0.5\n[signal]\nvalues = [1.0, 2.0, nan]\n',
        'kind = "diffusion"\n[signal.ball]\nvertex = 1\nradius = inf\n',
        'kind = "wks"\nenergy = -1e-300\nsigma = 1e300\n',
        'kind = "segmentation"\nsignature = "hks:t=0.1"\npersistence = 0.0\n',
        'kind = "distance"\nsource = 9223372036854775807\n',
    ]
    put_each("field_request", requests_toml, "toml-", b"\x01")
    h = "b65de4a870692d7b6461dff27d69139c2c29876bb9eadf3decb9bb25d108d3fc"
    experiments = {
        "diffusion-basis": f'experiment = "diffusion-basis"\nmesh = "sphere:res=2"\nmesh_hash = "{h}"\n'
                           'repair = false\nlaplacian = "fem"\nnormalize = true\nk = 20\nt = 0.1\n'
                           'anchor = 40\nout = "../direct"\n\n[figure]\nlevels = 10\ncolormap = "viridis"\n'
                           'view = "front"\nsize = 200\ntransparent = false\ncritical_points = true\n'
                           'colorbar = true\n',
        "field-heat": f'experiment = "field"\nmesh = "sphere:res=2"\nmesh_hash = "{h}"\nrepair = false\n'
                      'laplacian = "fem"\nnormalize = true\n\n[field]\nkind = "heat"\nanchor = 40\n'
                      't = 0.05\nkernel = "wfem"\nk = 20\n',
        "field-embedding": 'experiment = "field"\nmesh = "${SPECTRAL_MESH_SHARED_MESHES}/bunny00.off"\n'
                           'basis_k = 80\n\n[field]\nkind = "embedding"\nfilter = "commute"\n'
                           'component = 2\nk = 50\n',
        "harmonic": 'experiment = "harmonic"\nmesh = "../meshes/bunny.off"\nlaplacian = "cot"\norder = 1\n'
                    'constraints = [{ vertex = 12, value = 0.0 }, { vertex = 873, value = 1.0 }]\n'
                    'out = "bunny-harmonic"\n',
        "harmonic-counts": 'experiment = "harmonic"\nmesh = "torus:res=1"\nconstraints = [2, 4, 6]\norder = 2\n',
        "spectral-distance": 'experiment = "spectral-distance"\nmesh = "m.off"\nk = 50\n'
                             'distance = "wfem-diffusion:t=0.5"\nsource = 3\nbasis_k = 60\n',
        "bad-key": 'experiment = "harmonic"\nmesh = "x"\nk = 3\n',
        "bad-type": 'experiment = "field"\nmesh = "x"\n[field]\nkind = "heat"\nt = "soon"\n',
        "unknown": 'experiment = "nope"\nmesh = "x"\n',
        "no-field": 'experiment = "field"\nmesh = "x"\n',
        "basis-k-small": 'experiment = "spectral-distance"\nmesh = "x"\nk = 50\nbasis_k = 10\n',
        "figure-size": 'experiment = "field"\nmesh = "x"\n[field]\nkind = "hks"\n[figure]\nsize = 1\n',
        "syntax": 'experiment = "field\nmesh = \n',
    }
    put_each("experiment_file", experiments)
    web_body_seeds()
    total = 0
    for root, _, files in os.walk(OUT):
        for f in files:
            total += os.path.getsize(os.path.join(root, f))
    digest = hashlib.sha256()
    for root, _, files in sorted(os.walk(OUT)):
        for f in sorted(files):
            digest.update(open(os.path.join(root, f), "rb").read())
    print(f"seeds: {sum(len(f) for _, _, f in os.walk(OUT))} files, {total} bytes, "
          f"sha256 {digest.hexdigest()[:16]}")


if __name__ == "__main__":
    main()
