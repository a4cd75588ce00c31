"""Arrays in and out: axis order against analytic fields, buffers handed over without copies, layouts."""
import numpy as np
import pytest

import isowave


def grid(shape):
    """Index arrays z, y, x of an array of this (nz, ny, nx) shape."""
    return np.meshgrid(*(np.arange(n, dtype=np.float64) for n in shape), indexing="ij")


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_planes_land_on_their_world_axis(axis):
    """field[z, y, x] = index along one axis - c: every vertex lies on the plane, in world units, on the right axis."""
    shape, spacing, origin = (9, 11, 13), (0.5, 2.0, 1.25), (-3.0, 4.0, 10.0)  # spacing/origin are (x, y, z)
    c = 3.375
    field = grid(shape)[axis] - c
    vertices, faces = isowave.extract(field, 0.0, spacing=spacing, origin=origin)
    world = 2 - axis  # field axis 0 is z (column 2), axis 2 is x (column 0)
    assert len(vertices) > 0 and faces.shape[1] == 3
    np.testing.assert_allclose(vertices[:, world], origin[world] + c * spacing[world], rtol=0, atol=1e-9)
    extent = [(shape[2 - k] - 1) * spacing[k] for k in range(3)]
    for other in {0, 1, 2} - {world}:
        assert vertices[:, other].min() == pytest.approx(origin[other])
        assert vertices[:, other].max() == pytest.approx(origin[other] + extent[other])


def test_sphere_vertices_lie_on_the_sphere():
    """A distance field on an anisotropic grid: vertices within a small fraction of a cell of the sphere."""
    shape, spacing = (40, 30, 20), (1.5, 1.0, 0.75)  # nx=20 with sx=1.5 etc.: a box of ~28.5 x 29 x 29.25
    z, y, x = grid(shape)
    centre, radius = np.array([14.0, 14.5, 14.6]), 10.0
    p = np.stack([x * spacing[0], y * spacing[1], z * spacing[2]], axis=-1)
    field = radius - np.linalg.norm(p - centre, axis=-1)
    vertices, _ = isowave.extract(field, 0.0, spacing=spacing)
    distance = np.linalg.norm(vertices - centre, axis=1)
    np.testing.assert_allclose(distance, radius, atol=0.05)


def test_read_volume_hands_over_its_buffer():
    field, spacing, origin = isowave.read_volume("builtin:sphere:16")
    assert field.shape == (16, 16, 16) and field.dtype == np.float32
    assert not field.flags.owndata and type(field.base).__name__ == "PyCapsule"
    assert field.flags.c_contiguous and field.flags.writeable
    assert spacing == (1.0, 1.0, 1.0) and origin == (0.0, 0.0, 0.0)


def test_decode_hands_over_its_buffers(sphere_isw):
    path, _ = sphere_isw
    vertices, faces = isowave.decode(path)
    first, _ = isowave.decode(path)
    for array in (vertices, faces):
        assert not array.flags.owndata and type(array.base).__name__ == "PyCapsule"
    assert vertices.dtype == np.float64 and vertices.shape[1] == 3 and faces.dtype == np.uint32 and faces.shape[1] == 4
    assert not np.shares_memory(vertices, first)  # each call its own buffers
    assert faces.max() < len(vertices)


def test_every_layout_and_dtype_gives_the_same_surface():
    """Float64, Fortran order, a strided view and integers are read as the same samples (copies where needed)."""
    z, y, x = grid((12, 14, 16))
    field = (40 - np.sqrt((x - 7.5) ** 2 + (y - 6.5) ** 2 + (z - 5.5) ** 2) * 8).round()
    reference = isowave.extract(field.astype(np.float32), 0.5)
    padded = np.zeros((12, 14, 32))
    padded[:, :, ::2] = field
    for variant in (field, np.asfortranarray(field), padded[:, :, ::2], field.astype(np.int16)):
        vertices, faces = isowave.extract(variant, 0.5)
        np.testing.assert_array_equal(vertices, reference[0])
        np.testing.assert_array_equal(faces, reference[1])


def test_the_input_field_is_not_modified():
    field, _, _ = isowave.read_volume("builtin:sphere:16")
    before = field.copy()
    isowave.extract(field, 0.0, smooth=1.0)
    np.testing.assert_array_equal(field, before)
