"""The Python module as a user meets it (run by ctest with PYTHONPATH at <build>/python)."""
import json
import os
import subprocess
import threading
import time

import numpy as np
import pytest

import dpts

SOURCE = os.environ.get("DPTS_SOURCE", os.path.join(os.path.dirname(__file__), "..", ".."))
SAMPLE = os.path.join(SOURCE, "data", "olinda_dem_utm25s.tif")
DPTS_PAR = os.environ.get("DPTS_PAR", os.path.join(SOURCE, "build", "dpts-par"))


def ply_body(path):
    data = open(path, "rb").read()
    return data[data.index(b"end_header\n") + 11:]


def hills(n=600):
    """An n x n grid of smooth hills, 10 m cells, and its geotransform in UTM 11N."""
    c, r = np.meshgrid(np.arange(n), np.arange(n))
    z = 500 + 40 * np.sin(c * 0.05) * np.cos(r * 0.07) + 0.1 * r
    return z, (400000.0, 10.0, 0.0, 3800000.0, 0.0, -10.0)


@pytest.mark.parametrize("algo", ["vp", "pld", "vp-meta", "pld-meta", "qslim"])
def test_every_method_gives_dpts_par_mesh(tmp_path, algo):
    m = dpts.simplify(SAMPLE, keep=0.1, algo=algo)
    out, par = tmp_path / "py.ply", tmp_path / "par.ply"
    m.write(str(out))
    subprocess.run([DPTS_PAR, "--quiet", "--algo", algo, SAMPLE, str(par)], check=True)
    assert ply_body(out) == ply_body(par)


def test_simplify_a_file_gives_dpts_par_mesh(tmp_path):
    m = dpts.simplify(SAMPLE, keep=0.1)
    assert m.vertices.shape == (1232, 3) and m.vertices.dtype == np.float64
    assert m.faces.shape == (2395, 3) and m.faces.dtype == np.uint32
    assert m.faces.max() == 1231 and m.input_vertices == 12321
    assert m.crs.startswith('PROJCS["UTM Zone 25, Southern Hemisphere"')
    with pytest.raises(ValueError):
        m.vertices[0, 0] = 1  # a read-only view
    out = tmp_path / "py.ply"
    m.write(str(out))
    par = tmp_path / "par.ply"
    subprocess.run([DPTS_PAR, "--quiet", SAMPLE, str(par)], check=True)
    assert ply_body(out) == ply_body(par)


def test_simplify_an_array_with_its_georeferencing():
    z, gt = hills(200)
    z[50:60, 70:90] = np.nan  # a void
    m = dpts.simplify(z, geotransform=gt, crs="EPSG:32611", vertices=500)
    assert m.vertices.shape == (500, 3)
    x, y = m.vertices[:, 0], m.vertices[:, 1]
    assert x.min() == 400005 and x.max() == 400000 + 10 * 199 + 5
    assert 'UTM zone 11N' in m.crs
    # no vertex inside the void (cells 70..89 x 50..59)
    col, row = (x - 400005) / 10, (3799995 - y) / 10
    assert not np.any((col >= 70) & (col <= 89) & (row >= 50) & (row <= 59))
    # -9999 as no-data is the same void
    z2 = np.where(np.isnan(z), -9999.0, z)
    m2 = dpts.simplify(z2, geotransform=gt, crs="EPSG:32611", nodata=-9999, vertices=500)
    assert np.array_equal(m2.vertices, m.vertices) and np.array_equal(m2.faces, m.faces)


def test_usual_nodata_values_not_declared_are_heights_and_said():
    z, gt = hills(100)
    z[10:12, 20:30] = -9999.0  # voids that lost their no-data value
    m = dpts.simplify(z, geotransform=gt, crs="EPSG:32611", vertices=300)
    assert m.warnings == [
        "warning: an array of heights: 20 cells hold -9999, a usual no-data value, but band 1 "
        "has none: read as heights; if they are voids, give the band its no-data value "
        "(gdal_translate -a_nodata -9999 IN OUT)"]
    assert m.vertices[:, 2].min() < -9000  # the pit is kept
    tagged = dpts.simplify(z, geotransform=gt, crs="EPSG:32611", nodata=-9999, vertices=300)
    assert tagged.warnings == [] and tagged.vertices[:, 2].min() > 0
    whole = dpts.simplify(z, geotransform=gt, crs="EPSG:32611", vertices=300, algo="vp")
    assert whole.warnings == m.warnings


def test_write_by_extension(tmp_path):
    m = dpts.simplify(SAMPLE)
    for ext in ("obj", "stl", "gpkg"):
        m.write(str(tmp_path / ("m." + ext)))
    assert open(tmp_path / "m.obj").read().count("\nf ") == len(m.faces)
    assert (tmp_path / "m.stl").stat().st_size == 84 + 50 * len(m.faces)
    assert open(tmp_path / "m.gpkg", "rb").read(15) == b"SQLite format 3"
    m.write(str(tmp_path / "m.txt"), format="obj")
    assert open(tmp_path / "m.txt").read() == open(tmp_path / "m.obj").read()


def test_evaluate_returns_dpts_eval_figures(tmp_path):
    out = tmp_path / "m.ply"
    dpts.simplify(SAMPLE).write(str(out))
    r = dpts.evaluate(SAMPLE, str(out), points=12, sets=2)
    assert 0 < r["distance_error"] < 0.01
    assert len(r["distance_error_sets"]) == 2
    assert r["pairs_measured"] == 2 * 12 * 11 // 2
    assert r["mesh_vertices"] == 1232 and r["faces_over_nodata"] == 0
    assert r["vertical_rmse"] > 0 and r["geodesics"] == "straightened"
    # The same mesh in the other formats measures the same (STL and GeoPackage welded).
    m = dpts.simplify(SAMPLE)
    for name, ascii in (("m.obj", False), ("m.stl", True), ("m.gpkg", False)):
        m.write(str(tmp_path / name), ascii=ascii)
        other = dpts.evaluate(SAMPLE, str(tmp_path / name), points=12, sets=2)
        assert other["distance_error"] == pytest.approx(r["distance_error"], rel=1e-9), name
        assert other["mesh_vertices"] == 1232 and other["mesh_faces"] == r["mesh_faces"], name
    # The band measured is the one simplified: the sample has one.
    with pytest.raises(dpts.Error, match="no band 2"):
        dpts.evaluate(SAMPLE, str(out), points=12, sets=2, band=2)


def test_errors_name_the_file_or_option(tmp_path):
    with pytest.raises(dpts.Error, match="nonexistent.tif: no such file"):
        dpts.simplify(str(tmp_path / "nonexistent.tif"))
    with pytest.raises(dpts.Error, match="keep"):
        dpts.simplify(SAMPLE, keep=0)
    with pytest.raises(dpts.Error, match="algo qsim"):
        dpts.simplify(SAMPLE, algo="qsim")
    with pytest.raises(ValueError, match="geotransform"):
        dpts.simplify(np.zeros((5, 5)))
    with pytest.raises(dpts.Error, match="format las"):
        dpts.simplify(SAMPLE).write(str(tmp_path / "x.las"), format="las")
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_progress_is_called_and_can_stop_the_work():
    calls = []
    dpts.simplify(SAMPLE, progress=lambda f, stage: calls.append((f, stage)))
    assert calls and all(0 <= f <= 1 for f, _ in calls)
    with pytest.raises(dpts.Cancelled):
        dpts.simplify(SAMPLE, progress=lambda f, stage: False)

    def fails(f, stage):
        raise KeyError("from the callback")

    with pytest.raises(KeyError, match="from the callback"):
        dpts.simplify(SAMPLE, progress=fails)


def test_the_gil_is_released_while_dpts_works():
    z, gt = hills(900)
    done = threading.Event()
    result = {}

    def work():
        start = time.perf_counter()
        result["mesh"] = dpts.simplify(z, geotransform=gt, crs="EPSG:32611", threads=1)
        result["seconds"] = time.perf_counter() - start
        done.set()

    t = threading.Thread(target=work)
    ticks = 0
    t.start()
    while not done.is_set():  # this thread runs Python meanwhile: it needs the GIL
        ticks += 1
        time.sleep(0.002)
    t.join()
    assert result["mesh"].vertices.shape[0] == 81000
    # Held by dpts, the GIL would let this loop run only between its progress calls.
    assert ticks >= 0.2 * result["seconds"] / 0.002
