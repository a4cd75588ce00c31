"""Errors: isowave::Error becomes isowave.Error with the CLI's message; unsupported options say so."""
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


def test_decode_limits_by_bytes_and_error(sphere_isw):
    path, _ = sphere_isw
    size = path.stat().st_size
    whole, _ = isowave.decode(path)
    # A prefix decodes to a surface as large as the whole one; the whole file's bytes give the whole one.
    part, _ = isowave.decode(path, bytes=size * 3 // 4)
    assert part.shape == whole.shape
    assert (isowave.decode(path, bytes=size)[0] == whole).all()
    # An error below every recorded one reads the whole stream; a huge one the shortest prefix.
    assert (isowave.decode(path, max_error=1e-9)[0] == whole).all()
    coarse, _ = isowave.decode(path, max_error=1e9)
    assert coarse.shape == whole.shape
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
