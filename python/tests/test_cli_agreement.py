"""The module against the CLI's outputs on the same inputs (the CLI is the reference)."""
import json

import numpy as np
import pytest

import isowave


def read_obj(path, polygons=False):
    """Vertices and faces (0-based) of an ASCII OBJ file: an array of equal faces, or with polygons=True a
    list of faces of any size."""
    vertices, faces = [], []
    with open(path) as f:
        for line in f:
            fields = line.split()
            if fields and fields[0] == "v":
                vertices.append([float(x) for x in fields[1:4]])
            elif fields and fields[0] == "f":
                faces.append([int(x.split("/")[0]) - 1 for x in fields[1:]])
    return np.array(vertices), faces if polygons else np.array(faces)


def test_convert_of_a_path_writes_the_cli_bytes(cli, sphere_isw, tmp_path):
    cli_path, _ = sphere_isw
    summary = isowave.convert("builtin:sphere:32", 0.0, tmp_path / "sphere.isw", levels=3)
    assert (tmp_path / "sphere.isw").read_bytes() == cli_path.read_bytes()
    assert summary["output"] == str(tmp_path / "sphere.isw")
    assert summary["bytes"] == cli_path.stat().st_size


def test_convert_summary_has_the_cli_json_figures(sphere_isw, tmp_path):
    _, cli_result = sphere_isw
    summary = isowave.convert("builtin:sphere:32", 0.0, tmp_path / "sphere.isw", levels=3)
    for key in ("bytes", "volume_bytes", "extracted_vertices", "base_vertices", "fine_vertices", "levels",
                "fit_points_beyond_one_cell", "base_attempts"):
        assert summary[key] == cli_result[key], key
    for key in ("cell_size", "fit_isosurface_rms_cells", "quantization_rmse_percent_cell"):
        assert summary[key] == pytest.approx(cli_result[key], rel=1e-5), key
    assert len(summary["rows"]) == len(cli_result["rows"])
    for ours, theirs in zip(summary["rows"], cli_result["rows"]):
        assert ours["coefficients"] == theirs["coefficients"] and ours["bytes"] == theirs["bytes"]
        assert ours["base"] == theirs["base"]
        for key in ("percent", "rmse_percent_cell", "d_percent_cell"):
            assert ours[key] == pytest.approx(theirs[key], rel=1e-4, abs=1e-6), key
    assert set(summary["seconds"]) == set(cli_result["seconds"])
    assert set(summary["peak_megabytes"]) == set(cli_result["peak_megabytes"]) - {"load"}
    assert [level["fine_vertices"] for level in summary["fit_levels"]] == \
        [level["fine_vertices"] for level in cli_result["fit_levels"]]
    for ours, theirs in zip(summary["fit_levels"], cli_result["fit_levels"]):
        assert ours["d_percent_cell"] == pytest.approx(theirs["d_percent_cell"], rel=1e-4)


def test_convert_of_an_array_decodes_to_the_cli_mesh(sphere_isw, tmp_path):
    """The same field as an array (read_volume's) gives the CLI file's surface; only the metadata's source differs."""
    cli_path, _ = sphere_isw
    field, spacing, origin = isowave.read_volume("builtin:sphere:32")
    isowave.convert(field, 0.0, tmp_path / "array.isw", levels=3, spacing=spacing, origin=origin)
    for percent in (100, 10):
        ours = isowave.decode(tmp_path / "array.isw", percent=percent)
        theirs = isowave.decode(cli_path, percent=percent)
        np.testing.assert_array_equal(ours[0], theirs[0])
        np.testing.assert_array_equal(ours[1], theirs[1])


@pytest.mark.parametrize("percent,level", [(100, None), (5, None), (20, 1)])
def test_decode_gives_the_cli_decode_mesh(cli, sphere_isw, tmp_path, percent, level):
    cli_path, _ = sphere_isw
    obj = tmp_path / "decoded.obj"
    cli("decode", cli_path, "--percent", percent, "-o", obj, "--quiet",
        *(["--level", level] if level is not None else []))
    cli_vertices, cli_faces = read_obj(obj)
    vertices, faces = isowave.decode(cli_path, percent=percent, level=level)
    np.testing.assert_allclose(vertices, cli_vertices, rtol=1e-7, atol=1e-7)
    np.testing.assert_array_equal(faces, cli_faces)


def test_decode_by_coefficients_limit_and_triangulate_match_the_cli(cli, sphere_isw, tmp_path):
    cli_path, _ = sphere_isw
    obj = tmp_path / "decoded.obj"
    cli("decode", cli_path, "--coefficients", 300, "--limit", "--triangulate", "-o", obj, "--quiet")
    cli_vertices, cli_faces = read_obj(obj)
    vertices, faces = isowave.decode(cli_path, coefficients=300, limit=True, triangulate=True)
    assert faces.shape[1] == 3
    np.testing.assert_allclose(vertices, cli_vertices, rtol=1e-7, atol=1e-7)
    np.testing.assert_array_equal(faces, cli_faces)


@pytest.mark.parametrize("oracle", ["magnitude", "greedy"])
def test_decode_by_oracle_matches_the_cli(cli, sphere_isw, tmp_path, oracle):
    cli_path, _ = sphere_isw
    obj = tmp_path / "decoded.obj"
    cli("decode", cli_path, "--percent", 5, "--oracle", oracle, "-o", obj, "--quiet")
    cli_vertices, _ = read_obj(obj)
    vertices, _ = isowave.decode(cli_path, percent=5, oracle=oracle)
    np.testing.assert_allclose(vertices, cli_vertices, rtol=1e-7, atol=1e-7)
    # Another oracle keeps other coefficients: another surface.
    weighted, _ = isowave.decode(cli_path, percent=5)
    assert np.abs(weighted - vertices).max() > 1e-6


def test_stats_rows_are_the_cli_json_rows(cli, sphere_isw):
    cli_path, _ = sphere_isw
    theirs = json.loads(cli("stats", cli_path, "--json", "--percents", "100,20,10,5,2").stdout)["rows"]
    ours = isowave.stats(cli_path, [100, 20, 10, 5, 2])
    assert len(ours) == len(theirs)
    for row, reference in zip(ours, theirs):
        assert set(row) == set(reference)
        for key, value in reference.items():
            assert row[key] == pytest.approx(value, rel=1e-4, abs=1e-6), key


def test_read_volume_gives_the_samples_extract_contours(cli, tmp_path):
    """read_volume's array, extracted, gives the CLI's extract mesh (same surface, same vertex order)."""
    field, spacing, origin = isowave.read_volume("builtin:torus:24")
    obj = tmp_path / "torus.obj"
    cli("extract", "builtin:torus:24", "--iso", 0, "-o", obj, "--quiet")
    cli_vertices, cli_faces = read_obj(obj)
    vertices, faces = isowave.extract(field, 0.0, spacing, origin)
    np.testing.assert_allclose(vertices, cli_vertices, rtol=1e-7, atol=1e-7)
    np.testing.assert_array_equal(faces, cli_faces)


def test_a_cut_file_decodes_what_it_holds_with_the_cli_warning(cli, sphere_isw, tmp_path):
    cli_path, _ = sphere_isw
    data = cli_path.read_bytes()
    cut = tmp_path / "cut.isw"
    cut.write_bytes(data[: len(data) * 3 // 4])
    obj = tmp_path / "cut.obj"
    warning = cli("decode", cut, "--percent", 100, "-o", obj, "--quiet").stderr.strip()
    prefix = "isowave decode: warning: "
    assert warning.startswith(prefix)
    cli_vertices, cli_faces = read_obj(obj)
    with pytest.warns(UserWarning) as caught:
        vertices, faces = isowave.decode(cut)
    assert str(caught[0].message) == warning[len(prefix):]
    np.testing.assert_allclose(vertices, cli_vertices, rtol=1e-7, atol=1e-7)
    np.testing.assert_array_equal(faces, cli_faces)
    assert not np.array_equal(vertices, isowave.decode(cli_path)[0])


def test_decode_of_a_region_gives_the_cli_mesh_and_the_full_decode_inside(cli, sphere_isw, tmp_path):
    cli_path, _ = sphere_isw
    full, _ = isowave.decode(cli_path)
    low, high = full.min(axis=0), full.max(axis=0)
    box = np.concatenate([low, low + 0.4 * (high - low)])
    obj = tmp_path / "region.obj"
    # Outside the box the mesh keeps whole base faces, joined by polygons: triangles for arrays.
    cli("decode", cli_path, "--roi", ",".join(repr(float(v)) for v in box), "--triangulate", "-o", obj, "--quiet")
    cli_vertices, cli_faces = read_obj(obj)
    vertices, faces = isowave.decode(cli_path, roi=box, triangulate=True)
    np.testing.assert_allclose(vertices, cli_vertices, rtol=1e-7, atol=1e-7)
    np.testing.assert_array_equal(faces, cli_faces)
    # The full decode's points inside the box are all in the output, at their places.
    def inside(points):
        return points[np.all((points >= box[:3]) & (points <= box[3:]), axis=1)]
    ours, theirs = inside(vertices), inside(full)
    assert 0 < len(theirs) == len(ours) < len(full)
    nearest = np.min(np.linalg.norm(ours[:, None, :] - theirs[None, :, :], axis=2), axis=1)
    assert np.max(nearest) < 1e-9 * float(np.max(high - low))
    assert len(vertices) < len(full)
    with pytest.raises(isowave.Error, match="roi expects 6 numbers"):
        isowave.decode(cli_path, roi=(1, 2, 3))


def camera_below(path, distance, fov):
    """A camera `distance` surface heights below the surface of `path`, looking up at its centre; the surface."""
    full, _ = isowave.decode(path)
    low, high = full.min(axis=0), full.max(axis=0)
    centre = 0.5 * (low + high)
    camera = {"position": [float(centre[0]), float(centre[1]), float(low[2] - distance * (high[2] - low[2]))],
              "target": [float(v) for v in centre], "up": [0, 1, 0], "fov": fov, "viewport": [640, 480]}
    return camera, full


@pytest.mark.parametrize("cull", [False, True])
def test_decode_of_a_view_gives_the_cli_mesh_from_a_dict_or_a_file(cli, sphere_isw, tmp_path, cull):
    cli_path, _ = sphere_isw
    camera, full = camera_below(cli_path, 2, 20)
    path = tmp_path / "camera.json"
    path.write_text(json.dumps(camera))
    obj = tmp_path / "view.obj"
    cli("decode", cli_path, "--view", path, "--pixel-error", 2, "--triangulate", "-o", obj, "--quiet",
        *(["--cull-back-faces"] if cull else []))
    cli_vertices, cli_faces = read_obj(obj)
    for view in (camera, str(path)):
        vertices, faces = isowave.decode(cli_path, view=view, pixel_error=2, triangulate=True, cull_back_faces=cull)
        np.testing.assert_allclose(vertices, cli_vertices, rtol=1e-7, atol=1e-7)
        np.testing.assert_array_equal(faces, cli_faces)
    assert len(vertices) < len(full)
    with pytest.raises(isowave.Error, match="unknown key"):
        isowave.decode(cli_path, view=dict(camera, zoom=2))
    with pytest.raises(isowave.Error, match="view chooses"):
        isowave.decode(cli_path, view=camera, percent=5)


def test_culling_back_faces_keeps_the_far_side_whole(sphere_isw):
    cli_path, _ = sphere_isw
    camera, _ = camera_below(cli_path, 2, 40)
    culled = isowave.decode(cli_path, view=camera, pixel_error=0.5, cull_back_faces=True, triangulate=True)[1]
    assert len(culled) < len(isowave.decode(cli_path, view=camera, pixel_error=0.5, triangulate=True)[1])
    refiner = isowave.ViewRefiner(cli_path)
    refiner.set_view(camera, pixel_error=0.5, cull_back_faces=True)
    culled_levels = refiner.levels.copy()
    refiner.set_view(camera, pixel_error=0.5)
    assert (culled_levels <= refiner.levels).all() and (culled_levels < refiner.levels).any()
    with pytest.raises(isowave.Error, match="cull_back_faces needs a view"):
        isowave.decode(cli_path, cull_back_faces=True)


def test_view_refiner_patches_make_the_view_mesh_and_a_move_names_what_changed(sphere_isw):
    cli_path, _ = sphere_isw
    camera, full = camera_below(cli_path, 1.5, 30)
    low, high = full.min(axis=0), full.max(axis=0)
    refiner = isowave.ViewRefiner(cli_path)
    assert not refiner.levels.any()
    changed = refiner.set_view(camera, pixel_error=0.5)
    assert len(changed) > 0 and refiner.levels.max() > 0
    vertices, faces = refiner.mesh(triangulate=True)
    expected_vertices, expected_faces = isowave.decode(cli_path, view=camera, pixel_error=0.5, triangulate=True)
    np.testing.assert_array_equal(vertices, expected_vertices)
    np.testing.assert_array_equal(faces, expected_faces)
    everything = np.arange(len(refiner.levels), dtype=np.uint32)

    def by_face():
        owners, ends, corners = refiner.patches(everything)
        starts = np.concatenate([[0], ends[:-1]])
        patches = {}
        for owner, start, end in zip(owners, starts, ends):
            patches.setdefault(int(owner), []).append(tuple(corners[start:end]))
        return patches

    before = by_face()
    moved = dict(camera, position=[camera["position"][0] + 0.3 * float(high[0] - low[0]), *camera["position"][1:]])
    changed = set(refiner.set_view(moved, pixel_error=0.5).tolist())
    after = by_face()
    differ = {f for f in after if after[f] != before.get(f)}
    assert differ and differ <= changed
    assert len(refiner.set_view(moved, pixel_error=0.5)) == 0
    points = refiner.points
    assert points.shape[1] == 3 and not points.flags.writeable


@pytest.mark.parametrize("level", [0, 1, None])
def test_decode_polygons_gives_the_cli_polygons_and_per_vertex_levels(cli, sphere_isw, tmp_path, level):
    cli_path, _ = sphere_isw
    obj = tmp_path / "decoded.obj"
    cli("decode", cli_path, "--percent", 20, "-o", obj, "--quiet", *(["--level", level] if level is not None else []))
    cli_vertices, cli_faces = read_obj(obj, polygons=True)
    d = isowave.decode_polygons(cli_path, percent=20, level=level)
    np.testing.assert_allclose(d["vertices"], cli_vertices, rtol=1e-7, atol=1e-7)
    offsets, corners = d["offsets"], d["corners"]
    assert [corners[a:b].tolist() for a, b in zip(offsets[:-1], offsets[1:])] == cli_faces
    if level == 0:
        assert len(set(np.diff(offsets))) > 1  # the base mesh mixes polygons
    # Each level holds as many vertices as a decode at that level adds to the one below.
    counts = [len(isowave.decode_polygons(cli_path, level=l)["vertices"]) for l in range(4)]
    finest = 3 if level is None else level
    np.testing.assert_array_equal(np.bincount(d["level"], minlength=finest + 1), np.diff([0] + counts[:finest + 1]))
    assert np.all(d["detail"][d["level"] == 0] == 0)
    assert d["bytes_read"] <= d["file_bytes"] == cli_path.stat().st_size
    if level != 0:
        assert d["detail"].max() > 0
        # The base mesh alone keeps no coefficient: no detail anywhere.
        assert isowave.decode_polygons(cli_path, percent=0, level=level)["detail"].max() == 0
