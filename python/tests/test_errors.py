"""Errors: isowave::Error becomes isowave.Error with the CLI's message; unsupported options say so."""
import struct
import zlib

import numpy as np
import pytest

import isowave


def cli_message(result, command):
    """The CLI's one-line error without its 'isowave COMMAND: ' prefix."""
    prefix = f"isowave {command}: "
    line = result.stderr.strip()
    assert result.returncode != 0 and line.startswith(prefix), result.stderr
    return line[len(prefix):]


def test_missing_file_raises_the_cli_message(cli, tmp_path):
    missing = tmp_path / "missing.isw"
    expected = cli_message(cli("decode", missing, "--percent", 5, "-o", tmp_path / "x.ply", check=False), "decode")
    with pytest.raises(isowave.Error) as caught:
        isowave.decode(missing, percent=5)
    assert str(caught.value) == expected
    assert caught.value.kind == "i/o error"
    assert isinstance(caught.value, RuntimeError)


def test_missing_volume_raises_the_cli_message(cli, tmp_path):
    missing = tmp_path / "missing.nrrd"
    expected = cli_message(cli("extract", missing, "--iso", 1, "-o", tmp_path / "x.ply", check=False), "extract")
    with pytest.raises(isowave.Error, match="^" + expected.replace(".", r"\.") + "$"):
        isowave.read_volume(missing)


def test_corrupt_file_raises_a_format_error(sphere_isw, tmp_path):
    path, _ = sphere_isw
    data = bytearray(path.read_bytes())
    data[40] ^= 0xFF
    corrupt = tmp_path / "corrupt.isw"
    corrupt.write_bytes(bytes(data))
    with pytest.raises(isowave.Error) as caught:
        isowave.decode(corrupt)
    assert caught.value.kind == "format error"
    assert str(corrupt) in str(caught.value)


def rate_table(path):
    """The file's cell size (META) and RDTB rows (stream bytes, D in world units), read as docs/FORMAT.md lays
    them out: a 16-byte header, then sections of tag, u64 size, u32 CRC, payload, u32 CRC."""
    data, at, cell, rows = path.read_bytes(), 16, None, []
    while at + 16 <= len(data):
        tag, size = data[at:at + 4], struct.unpack_from("<Q", data, at + 4)[0]
        payload = data[at + 16:at + 16 + size]
        if tag == b"META":  # u32 text size, the text compressed by zlib
            text = zlib.decompress(payload[4:]).decode()
            cell = float(dict(line.split("=", 1) for line in text.splitlines())["cell_size"])
        elif tag == b"RDTB":
            rows = [struct.unpack_from("<Qd", payload, 4 + 16 * k) for k in range(struct.unpack_from("<I", payload)[0])]
        at += 20 + size
    return cell, rows


def test_decode_limits_by_bytes_and_error(sphere_isw):
    path, _ = sphere_isw
    size = path.stat().st_size
    whole, faces = isowave.decode(path)

    def distance(decode):
        """RMS distance of a limited decode's vertices from the whole decode's (the same fine mesh)."""
        vertices, limited_faces = decode
        assert vertices.shape == whole.shape and (limited_faces == faces).all()
        return float(np.sqrt(((vertices - whole) ** 2).sum(axis=1).mean()))

    # Fewer bytes decode the same mesh farther from the whole one; the whole file's bytes give the whole one.
    half, three_quarters = (distance(isowave.decode(path, bytes=size * k // 4)) for k in (2, 3))
    assert half > three_quarters > 0
    assert distance(isowave.decode(path, bytes=size)) == 0
    # Each error the file records picks a longer prefix than the one before, closer to the whole decode; an error
    # below every row reads the whole stream, a huge one the shortest prefix.
    cell, rows = rate_table(path)
    assert len(rows) >= 3 and [b for b, _ in rows] == sorted(b for b, _ in rows)
    by_row = [distance(isowave.decode(path, max_error=error / cell * (1 + 1e-9))) for _, error in rows]
    assert all(coarser > finer for coarser, finer in zip(by_row, by_row[1:])), by_row
    assert distance(isowave.decode(path, max_error=1e9)) == by_row[0] > 0
    assert distance(isowave.decode(path, max_error=1e-9)) == 0
    with pytest.raises(isowave.Error, match="at most one of max_error and bytes"):
        isowave.decode(path, bytes=4000, max_error=0.1)
    with pytest.raises(isowave.Error, match="max_error must be a positive"):
        isowave.decode(path, max_error=-1)


def test_bad_arguments(sphere_isw, tmp_path):
    path, _ = sphere_isw
    with pytest.raises(isowave.Error, match="percent must be in 0..100"):
        isowave.decode(path, percent=150)
    with pytest.raises(isowave.Error, match="at most one of percent and coefficients"):
        isowave.decode(path, percent=5, coefficients=10)
    with pytest.raises(isowave.Error, match="oracle must be weighted, magnitude or greedy"):
        isowave.decode(path, percent=5, oracle="best")
    with pytest.raises(isowave.Error, match="oracle chooses what percent or coefficients keep"):
        isowave.decode(path, oracle="greedy")
    with pytest.raises(isowave.Error, match=r"level must be in 0\.\.3"):
        isowave.decode(path, level=4)
    with pytest.raises(TypeError, match="unexpected keyword argument 'colour'"):
        isowave.convert("builtin:sphere:16", 0.0, tmp_path / "x.isw", colour="red")
    with pytest.raises(isowave.Error, match="levels must be in 1..6"):
        isowave.convert("builtin:sphere:16", 0.0, tmp_path / "x.isw", levels=9)
    with pytest.raises(isowave.Error, match="convert writes .isw files"):
        isowave.convert("builtin:sphere:16", 0.0, tmp_path / "x.ply")
    with pytest.raises(ValueError, match="3-D array"):
        isowave.extract(np.zeros((4, 4)), 0.0)
    assert not (tmp_path / "x.isw").exists()


def test_convert_refuses_to_replace_a_file_without_force(sphere_isw, tmp_path):
    path = tmp_path / "existing.isw"
    path.write_bytes(b"keep me")
    with pytest.raises(isowave.Error, match="already exists"):
        isowave.convert("builtin:sphere:16", 0.0, path)
    assert path.read_bytes() == b"keep me"


def test_an_isovalue_outside_the_field_gives_an_empty_mesh_and_convert_refuses_it(tmp_path):
    vertices, faces = isowave.extract(np.zeros((8, 8, 8), np.float32), 1.0)
    assert vertices.shape == (0, 3) and faces.shape == (0, 3)
    with pytest.raises(isowave.Error) as caught:
        isowave.convert(np.zeros((8, 8, 8), np.float32), 1.0, tmp_path / "empty.isw")
    assert caught.value.kind == "empty result"
