#!/usr/bin/env python3
"""Writes the seed corpora of fuzz/corpus/ (small valid files of each format
and variant, plus past findings' shapes). The .vdb seeds need OpenVDB: this
compiles and runs vdb_seeds.cpp. The .isw seed is the codec's golden file.
Run from anywhere: fuzz/make_seeds.py"""
import base64, gzip, os, shutil, struct, subprocess, sys, tempfile, zlib

HERE = os.path.dirname(os.path.abspath(__file__))
CORPUS = os.path.join(HERE, "corpus")
VALUES = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]  # a 2x2x2 volume
ASCII = " ".join(str(int(v)) for v in VALUES)


def write(sub, name, data):
    os.makedirs(os.path.join(CORPUS, sub), exist_ok=True)
    with open(os.path.join(CORPUS, sub, name), "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)


def floats(fmt):
    return struct.pack(fmt + "8f", *VALUES)


def raw():
    # Byte 0: dims x-1 | (y-1) << 3; byte 1: z-1 | type << 3 | big-endian << 6.
    write("raw", "float_2x2x2", bytes([1 | 1 << 3, 1 | 6 << 3]) + floats("<"))
    write("raw", "uint16_be_3x2x1", bytes([2 | 1 << 3, 0 | 2 << 3 | 1 << 6]) + struct.pack(">6H", *range(6)))
    write("raw", "double_2x1x1", bytes([1, 7 << 3]) + struct.pack("<2d", 0.5, -1e300))


def nrrd():
    head = "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nspace directions: (1,0,0) (0,2,0) (0,0,0.5)\n" \
           "space origin: (1,2,3)\n"
    write("nrrd", "raw.nrrd", (head + "encoding: raw\nendian: little\n\n").encode() + floats("<"))
    write("nrrd", "ascii.nrrd", "NRRD0005\n# c\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nspacings: 1 1 1\n"
          "encoding: ascii\nline skip: 0\nbyte skip: 0\nkey:=value\n\n" + ASCII + "\n")
    write("nrrd", "gzip.nrrd", ("NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nencoding: gzip\nendian: big\n\n")
          .encode() + gzip.compress(struct.pack(">8h", *range(8)), mtime=0))


def vtk():
    head = "# vtk DataFile Version 3.0\nseed\n{}\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\nORIGIN 0 0 0\n" \
           "SPACING 1 1 1\nPOINT_DATA 8\n"
    write("vtk", "ascii.vtk", head.format("ASCII") + "VECTORS v float\n" + " ".join(["1"] * 24) +
          "\nFIELD fd 1\nf%20a 1 8 int\n" + ASCII + "\nSCALARS s float 1\nLOOKUP_TABLE default\n" + ASCII + "\n")
    write("vtk", "binary.vtk", (head.format("BINARY") + "SCALARS s double\nLOOKUP_TABLE default\n").encode() +
          struct.pack(">8d", *VALUES) + b"\nCELL_DATA 1\nSCALARS c int\nLOOKUP_TABLE default\n\x00\x00\x00\x01\n")


def vti():
    def doc(attrs, data_array, appended=b""):
        return (b'<?xml version="1.0"?>\n<VTKFile type="ImageData" version="1.0" byte_order="LittleEndian" ' +
                attrs + b'>\n<ImageData WholeExtent="0 1 0 1 0 1" Origin="0 0 0" Spacing="1 1 1" '
                b'Direction="1 0 0 0 1 0 0 0 1">\n<Piece Extent="0 1 0 1 0 1"><PointData Scalars="s">' +
                data_array + b"</PointData></Piece>\n</ImageData>\n" + appended + b"</VTKFile>\n")
    payload = floats("<")
    write("vti", "ascii.vti", doc(b"", b'<DataArray type="Float32" Name="s" format="ascii">' + ASCII.encode() +
                                  b"</DataArray>"))
    write("vti", "base64.vti", doc(b'header_type="UInt32"', b'<DataArray type="Float32" Name="s" format="binary">' +
                                   base64.b64encode(struct.pack("<I", len(payload)) + payload) + b"</DataArray>"))
    block = zlib.compress(payload)
    header = struct.pack("<QQQQ", 1, len(payload), len(payload), len(block))
    write("vti", "zlib_appended.vti",
          doc(b'header_type="UInt64" compressor="vtkZLibDataCompressor"',
              b'<DataArray type="Float32" Name="s" format="appended" offset="0"/>',
              b'<AppendedData encoding="raw">\n_' + header + block + b"\n</AppendedData>\n"))


def mesh():
    write("mesh", "quad.obj", "# seed\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3//1 -1\n")
    write("mesh", "tetra.off", "OFF\n# c\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n3 1 2 3\n3 0 2 3 255 0 0\n")
    write("mesh", "ascii.ply", "ply\nformat ascii 1.0\ncomment c\nelement vertex 3\nproperty float x\nproperty float y\n"
          "property float z\nproperty uchar sharp\nelement face 1\nproperty list uchar int vertex_indices\n"
          "end_header\n0 0 0 1\n1 0 0 0\n0 1 0 0\n3 0 1 2\n")
    # Binary, float-typed lists in the vertex and face elements (finding 1's shape) and an extra element.
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nproperty list float float extra\nelement face 1\n"
            "property list float float vertex_indices\nelement other 1\nproperty list uchar int v\nend_header\n")
    body = b"".join(struct.pack("<3f", *p) + struct.pack("<f", 0) for p in [(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    write("mesh", "binary_float_lists.ply", head.encode() + body + struct.pack("<4f", 3, 0, 1, 2) + b"\x01" +
          struct.pack("<i", 7))
    write("mesh", "big_endian.ply", b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\n"
          b"property double y\nproperty double z\nelement face 1\nproperty list uint uint vertex_indices\n"
          b"end_header\n" + struct.pack(">9d", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack(">4I", 3, 0, 1, 2))


def isw_sections(data):
    """The 16-byte header and each section (tag, u64 size, CRC, payload, CRC) of an .isw file."""
    parts, at = [data[:16]], 16
    while at + 16 <= len(data):
        size = struct.unpack_from("<Q", data, at + 4)[0]
        parts.append(data[at:at + 20 + size])
        at += 20 + size
    return parts


def isw_section(tag, payload):
    size = struct.pack("<Q", len(payload))
    return tag + size + struct.pack("<I", zlib.crc32(tag + size)) + payload + struct.pack("<I", zlib.crc32(tag + payload))


def isw():
    data = os.path.join(HERE, "..", "tests", "codec", "data")
    shutil.copy(os.path.join(data, "golden_1_0.isw"), os.path.join(CORPUS, "isw", "golden_1_0.isw"))
    shutil.copy(os.path.join(data, "golden_2_0.isw"), os.path.join(CORPUS, "isw", "golden_2_0.isw"))
    with open(os.path.join(data, "golden_2_0.isw"), "rb") as f:
        golden = f.read()
    # Version 2 decodes any prefix past its headers: one cut inside the plane stream.
    write("isw", "golden_2_0_cut_in_stream.isw", golden[:600])
    # Stream sections a reader must reject (issue #52): PLNS repeated, RDTB after PLNS; and RDTB in its place.
    head, planes, end = isw_sections(golden)[:5], isw_sections(golden)[5], isw_sections(golden)[6]
    assert planes[:4] == b"PLNS" and end[:4] == b"END "
    rates = isw_section(b"RDTB", struct.pack("<IQdQd", 2, 100, 0.01, 284, 0.001))
    write("isw", "golden_2_0_plns_repeated.isw", b"".join(head) + planes + planes + end)
    write("isw", "golden_2_0_rdtb_after_plns.isw", b"".join(head) + planes + rates + end)
    write("isw", "golden_2_0_rdtb.isw", b"".join(head) + rates + planes + end)
    # Version 2.1 (non-normal flags in the planes): the golden file, a cut, and its planes under a 2.0 header
    # (PLNS's coding flag and the header's minor version disagree: a reader must reject it).
    shutil.copy(os.path.join(data, "golden_2_1.isw"), os.path.join(CORPUS, "isw", "golden_2_1.isw"))
    with open(os.path.join(data, "golden_2_1.isw"), "rb") as f:
        golden21 = f.read()
    write("isw", "golden_2_1_cut_in_stream.isw", golden21[:500])
    assert golden21[8:12] == b"\x02\x00\x01\x00"
    write("isw", "golden_2_1_minor_0.isw", golden21[:10] + b"\x00\x00" + golden21[12:])
    # Version 2.2 (groups by space, GIDX): the golden file, a cut inside GIDX, and PLNS without its GIDX.
    shutil.copy(os.path.join(data, "golden_2_2.isw"), os.path.join(CORPUS, "isw", "golden_2_2.isw"))
    with open(os.path.join(data, "golden_2_2.isw"), "rb") as f:
        golden22 = f.read()
    sections22 = isw_sections(golden22)
    assert sections22[5][:4] == b"GIDX" and sections22[6][:4] == b"PLNS"
    offset = golden22.index(b"GIDX")
    write("isw", "golden_2_2_cut_in_index.isw", golden22[:offset + 16 + (len(sections22[5]) - 20) // 2])
    write("isw", "golden_2_2_no_index.isw", b"".join(sections22[:5]) + b"".join(sections22[6:]))
    # 2.2 with PCNT (plane counts) between GIDX and PLNS.
    shutil.copy(os.path.join(data, "golden_2_2_counts.isw"), os.path.join(CORPUS, "isw", "golden_2_2_counts.isw"))


def npy():
    def file(descr, fortran, shape, data, major=1):
        header = "{'descr': '%s', 'fortran_order': %s, 'shape': %s, }" % (descr, fortran, shape)
        prefix = 10 if major == 1 else 12
        header += " " * (-(prefix + len(header) + 1) % 64) + "\n"
        length = struct.pack("<H" if major == 1 else "<I", len(header))
        return b"\x93NUMPY" + bytes([major, 0]) + length + header.encode("latin-1") + data
    write("npy", "f4_c.npy", file("<f4", False, "(2, 2, 2)", floats("<")))
    write("npy", "i2_be_fortran.npy", file(">i2", True, "(3, 2, 1)", struct.pack(">6h", *range(-3, 3))))
    write("npy", "f8_v2.npy", file("<f8", False, "(1, 1, 2)", struct.pack("<2d", 0.5, -1e300), 2))
    write("npy", "u1_v3.npy", file("|u1", False, "(2, 2, 2)", bytes(range(8)), 3))
    write("npy", "f2.npy", file("<f2", False, "(1, 2, 2)", struct.pack("<4e", 1.0, -2.0, 65504.0, 6e-8)))


def vdb():
    with tempfile.TemporaryDirectory() as tmp:
        exe = os.path.join(tmp, "vdb_seeds")
        subprocess.run(["c++", "-std=c++17", "-O1", os.path.join(HERE, "vdb_seeds.cpp"), "-o", exe, "-lopenvdb",
                        "-ltbb", "-lImath-3_1"], check=True)
        subprocess.run([exe, os.path.join(CORPUS, "vdb")], check=True)


if __name__ == "__main__":
    for make in (raw, nrrd, vtk, vti, npy, mesh, isw, vdb):
        os.makedirs(os.path.join(CORPUS, make.__name__), exist_ok=True)
        make()
    sys.exit(0)
