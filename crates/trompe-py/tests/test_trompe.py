"""The Python package against the library and the command line: every entry point, bad input
raised with the command line's message, arrays of the right shape and dtype, the same figures
as ``trompe --json`` for the same bake.

Run from anywhere after installing the wheel (``.ci/run`` does): ``pytest crates/trompe-py/tests``.
The ``trompe`` binary compared against is ``target/release/trompe`` (or ``$TROMPE_BIN``).
"""

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import trompe

ROOT = Path(__file__).resolve().parents[3]
ASSETS = ROOT / "assets"
SCENES = ROOT / "scenes"
BIN = os.environ.get("TROMPE_BIN", str(ROOT / "target" / "release" / "trompe"))


def cli(*args):
    """The command line's run: (exit code, stdout, stderr)."""
    done = subprocess.run([BIN, *map(str, args)], capture_output=True, text=True, cwd=ROOT)
    return done.returncode, done.stdout, done.stderr


def cli_json(*args):
    code, out, err = cli("--json", *args)
    assert code == 0, err
    return json.loads(out)["result"]


def test_load_mesh_gives_its_summary_and_geometry_as_arrays():
    mesh = trompe.load_mesh(ASSETS / "meshes" / "teapot.obj")
    assert mesh.positions.dtype == np.float32 and mesh.positions.shape[1] == 3
    assert mesh.triangles.dtype == np.uint32 and mesh.triangles.shape == (mesh.info["triangles"], 3)
    assert mesh.positions.shape[0] == mesh.info["vertices"]
    assert int(mesh.triangles.max()) < mesh.positions.shape[0]
    lo, hi = mesh.positions.min(axis=0), mesh.positions.max(axis=0)
    assert np.allclose(lo, mesh.info["bounds"]["min"]) and np.allclose(hi, mesh.info["bounds"]["max"])
    assert mesh.info == cli_json("info", ASSETS / "meshes" / "teapot.obj")


def test_a_bad_file_raises_the_command_lines_message(tmp_path):
    broken = tmp_path / "broken.obj"
    broken.write_text("v 0 0 0\nf 1 2 9\n")
    for call, args in [
        (trompe.load_mesh, ("info", broken)),
        (trompe.read_image, ("compare", broken, broken)),
    ]:
        with pytest.raises(trompe.TrompeError) as raised:
            call(broken)
        code, _, err = cli(*args)
        assert code == 1
        message = str(raised.value)
        assert str(broken) in message, message
        assert err.strip() == f"error: {message}", (err, message)


def test_bad_arguments_are_refused_by_name(tmp_path):
    teapot = ASSETS / "meshes" / "teapot.obj"
    with pytest.raises(trompe.TrompeError, match="camera"):
        trompe.bake_impostor(teapot, tmp_path / "a.json", camera="fisheye")
    with pytest.raises(trompe.TrompeError, match="resolution"):
        trompe.bake_impostor(teapot, tmp_path / "a.json", resolution=0)
    with pytest.raises(trompe.TrompeError, match="warp"):
        trompe.render(SCENES / "diffuse.toml", "warp")
    # An output that is one of the files the mesh reads: refused before any work, untouched.
    mesh = tmp_path / "pot.obj"
    mesh.write_text("mtllib pot.json\n" + teapot.read_text())
    (tmp_path / "pot.json").write_text("newmtl default\nKd 0.5 0.5 0.5\n")
    before = (tmp_path / "pot.json").read_bytes()
    with pytest.raises(trompe.TrompeError, match="pot.json"):
        trompe.bake_impostor(mesh, tmp_path / "pot.json", resolution=8)
    assert (tmp_path / "pot.json").read_bytes() == before


def test_a_bake_reports_what_the_command_line_reports(tmp_path):
    bunny = ASSETS / "meshes" / "bunny.obj"
    report = trompe.bake_impostor(bunny, tmp_path / "py.json", resolution=64)
    same = cli_json("impostor", "bake", bunny, "--resolution", 64, "-o", tmp_path / "cli.json")
    for key in ["kind", "resolution", "coverage", "layers", "map_bytes"]:
        assert report[key] == same[key], key
    assert Path(report["files"][0]).is_file() and set(report["timings"]) == set(same["timings"])
    # The sidecar it wrote reads back, and checks against the exact BVH.
    described = trompe.info(tmp_path / "py.json")
    assert described["camera"] == "spoc" and described["coverage"] == pytest.approx(report["coverage"])
    checked = trompe.check_impostor(bunny, tmp_path / "py.json", rays=2000)
    by_cli = cli_json("impostor", "check", bunny, "--impostor", tmp_path / "py.json", "--rays", 2000)
    assert checked["fidelity"] == by_cli["fidelity"]
    assert 0.5 < checked["fidelity"]["agreement"] <= 1.0
    built = trompe.check_impostor(bunny, camera="pinhole", resolution=64)
    assert built["impostor"]["camera"] == "pinhole" and built["fidelity"]["rays"] > 0


def test_a_folder_bakes_to_octahedral_atlases_with_progress(tmp_path):
    lib = tmp_path / "lib"
    (lib / "a").mkdir(parents=True)
    (lib / "b").mkdir()
    teapot = (ASSETS / "meshes" / "teapot.obj").read_text()
    (lib / "a" / "pot.obj").write_text(teapot)
    (lib / "b" / "pot.obj").write_text(teapot)
    seen = []
    manifest = trompe.bake_octahedral(
        lib, tmp_path / "out", frames=4, resolution=64, progress=lambda d, n, p: seen.append((d, n))
    )
    assert seen == [(1, 2), (2, 2)]
    assert len(manifest["entries"]) == 2 and all(e["error"] is None for e in manifest["entries"])
    for folder in ["a", "b"]:
        assert (tmp_path / "out" / folder / "pot.json").is_file()
    assert trompe.info(tmp_path / "out" / "a" / "pot.json")["grid"]["n"] == 4
    # Again with skip_existing: nothing baked again, the same outputs.
    again = trompe.bake_octahedral(lib, tmp_path / "out", frames=4, resolution=64, skip_existing=True)
    strip = lambda m: [{k: v for k, v in e.items() if k != "seconds"} for e in m["entries"]]
    assert strip(again) == strip(manifest)
    # A file of the user's where a map would go is refused, before any work, and kept.
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "a").mkdir()
    (mine / "a" / "pot.png").write_bytes(b"my texture")
    with pytest.raises(trompe.TrompeError, match="pot.png"):
        trompe.bake_octahedral(lib, mine, frames=4, resolution=64)
    assert (mine / "a" / "pot.png").read_bytes() == b"my texture"
    # A progress callback that raises stops the batch with its exception.
    def stop(done, total, path):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        trompe.bake_octahedral(lib, tmp_path / "out2", frames=4, resolution=64, progress=stop)


def test_views_are_captured_scored_and_rendered(tmp_path):
    duck = ASSETS / "gltf" / "Duck.glb"
    captured = trompe.capture_views(duck, tmp_path / "cap", count=8, size=(96, 72))
    assert captured["views"] == 8 and (tmp_path / "cap" / "cameras.txt").is_file()
    scores = trompe.score_views(tmp_path / "cap", duck, weights=["ulr"], every=4)
    by_cli = cli_json("views", "score", tmp_path / "cap", "--mesh", duck, "--weights", "ulr", "--every", 4)
    assert scores == by_cli
    image = trompe.render_views(tmp_path / "cap", duck, SCENES / "diffuse.toml")
    assert image.dtype == np.float32 and image.ndim == 3 and image.shape[2] == 4
    assert (image[..., 3] > 0).any()


def test_every_method_renders_a_frame_of_the_size_asked():
    assert "trace" in trompe.methods() and "octahedral" in trompe.methods()
    trace = trompe.render(SCENES / "diffuse.toml", "trace", size=(64, 48))
    assert trace.color.shape == (48, 64, 4) and trace.color.dtype == np.float32
    assert trace.object_id.shape == (48, 64) and trace.object_id.dtype == np.uint32
    assert trace.depth.shape == (48, 64) and trace.depth.dtype == np.float32
    raster = trompe.render(SCENES / "diffuse.toml", "raster", size=(64, 48))
    # Two methods of one diffuse scene see the same objects almost everywhere.
    assert (trace.object_id == raster.object_id).mean() > 0.95
    assert np.isfinite(trace.color).all() and (trace.object_id != 0xFFFFFFFF).any()


def test_images_compare_as_the_command_line_compares_them(tmp_path):
    for method in ["trace", "raster"]:
        code, _, err = cli("-q", "render", SCENES / "diffuse.toml", "--method", method, "-o", tmp_path / f"{method}.png")
        assert code == 0, err
    a, b = tmp_path / "trace.png", tmp_path / "raster.png"
    scores = trompe.compare(a, b)
    same = cli_json("compare", a, b)
    assert scores == {k: same[k] for k in ["psnr_db", "ssim", "flip"]}
    image = trompe.read_image(a)
    assert image.shape == (320, 480, 4) and image.dtype == np.float32


def test_the_folder_example_bakes_with_its_progress_bar(tmp_path):
    import sys

    example = ROOT / "crates" / "trompe-py" / "examples" / "bake_folder.py"
    done = subprocess.run(
        [sys.executable, str(example), str(ASSETS / "meshes"), str(tmp_path / "out"), "--frames", "4", "--resolution", "64"],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    assert "3 of 3 meshes baked" in done.stdout
    assert "3/3" in done.stderr
    assert (tmp_path / "out" / "teapot.json").is_file()
