"""``vobscure estimate``: one estimate of a user's frame (or a sequence) from files."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

import blender_frames
import vobscure as vo
from vobscure import cli
from vobscure import io as vio

pytest.importorskip("OpenEXR")

SIZE = (24, 16)
RADIUS = 0.5
#: The CLI's estimate against the library's on the original G-buffer (both float32).
TOL = 1e-6


@pytest.fixture(scope="module")
def frame(tmp_path_factory):
    """The crease written as Blender would (world normals, 1e10 background) and its pose."""
    d = tmp_path_factory.mktemp("frame")
    scene = vo.scenes.get("crease")
    gb = vo.render_gbuffer(scene, scene.camera(SIZE))
    cam = gb.camera
    channels = {"View Layer.Depth.Z": np.where(gb.valid, gb.depth, 1e10).astype(np.float32)}
    for k, axis in enumerate("XYZ"):
        channels[f"View Layer.Normal.{axis}"] = gb.world_normal[:, :, k].astype(np.float32)
    import OpenEXR

    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
                 channels).write(str(d / "frame.exr"))
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = cam.right, cam.up, -cam.forward, cam.eye
    np.savetxt(d / "pose.txt", pose)
    return {"dir": d, "exr": d / "frame.exr", "pose": d / "pose.txt", "gb": gb}


def _blender_args(frame):
    return ["--pose", str(frame["pose"]), "--normal-space", "world", "--background", "1e10"]


def _expected(gb, **kwargs):
    return vo.vo_line(gb.astype(np.float32), radius=RADIUS, samples=9, seed=0, **kwargs)


def _run(capsys, *argv):
    status = cli.main(["estimate", *map(str, argv)])
    out = capsys.readouterr()
    return status, out.out, out.err


def test_one_frame_matches_the_library(frame, tmp_path, capsys):
    out = tmp_path / "vo.exr"
    status, stdout, _ = _run(capsys, "--depth", frame["exr"], "--fov", frame["gb"].camera.fov_y,
                             *_blender_args(frame), "--radius", RADIUS, "--normal-clamp", "--out", out)
    assert status == 0
    got = vio.exr_channels(out)["Y"]
    expected = _expected(frame["gb"], normal_clamp=True)
    np.testing.assert_array_equal(np.isnan(got), np.isnan(expected))
    assert np.nanmax(np.abs(got - expected)) <= TOL
    assert "line:9 radius 0.5 normal clamp" in stdout and f"wrote {out}" in stdout


def test_intrinsics_and_projection_give_the_fov_camera(frame, tmp_path, capsys):
    W, H = SIZE
    f = (H / 2) / np.tan(np.radians(frame["gb"].camera.fov_y) / 2)
    near, far = 0.1, 100.0
    P = np.zeros((4, 4))  # glFrustum of the symmetric frustum
    P[0, 0], P[1, 1] = 2 * f / W, 2 * f / H
    P[2, 2], P[2, 3], P[3, 2] = -(far + near) / (far - near), -2 * far * near / (far - near), -1.0
    np.savetxt(tmp_path / "P.txt", P)
    outs = {}
    for name, lens in (("fov", ["--fov", frame["gb"].camera.fov_y]),
                       ("intrinsics", ["--intrinsics", f, f, W / 2, H / 2]),
                       ("projection", ["--projection", tmp_path / "P.txt"])):
        outs[name] = tmp_path / f"{name}.npy"
        status, _, err = _run(capsys, "--depth", frame["exr"], *lens, *_blender_args(frame),
                              "--radius", RADIUS, "--normal-clamp", "--quiet", "--out", outs[name])
        assert status == 0, err
    fov = np.load(outs["fov"])
    for name in ("intrinsics", "projection"):
        np.testing.assert_allclose(np.load(outs[name]), fov, atol=TOL, err_msg=name)


def test_png_blur_and_view_space_npz(frame, tmp_path, capsys):
    vio.write_gbuffer(tmp_path / "f.npz", frame["gb"])   # view-space normals, inf background
    out = tmp_path / "vo.png"
    status, _, err = _run(capsys, "--depth", tmp_path / "f.npz", "--fov", frame["gb"].camera.fov_y,
                          "--radius", RADIUS, "--blur", "--bits", "16", "--method", "point:12",
                          "--thickness", 0.3, "--quiet", "--out", out)
    assert status == 0, err
    from PIL import Image

    with Image.open(out) as im:
        png = np.asarray(im)
    assert png.dtype == np.uint16 and png.shape == (SIZE[1], SIZE[0])
    assert (png[~frame["gb"].valid] == 0).all() and (png[frame["gb"].valid] > 0).all()


def test_quiet_prints_nothing_and_large_frames_get_a_progress_bar(frame, tmp_path, capsys, monkeypatch):
    args = ["--depth", frame["exr"], "--fov", 40, *_blender_args(frame), "--radius", RADIUS]
    assert _run(capsys, *args, "--quiet", "--out", tmp_path / "a.exr")[1:] == ("", "")
    monkeypatch.setattr(cli, "ESTIMATE_PROGRESS_PIXELS", 1)
    _, stdout, err = _run(capsys, *args, "--out", tmp_path / "b.exr")
    assert "frame.exr:" in err and "/3 [" in err   # the stages: convert, estimate, write
    assert "mean visibility" in stdout


def test_a_sequence_runs_frame_by_frame_and_reports_flicker(frame, tmp_path, capsys):
    frames = tmp_path / "frames"
    frames.mkdir()
    for k in range(3):   # the same frame three times: same seed, so no flicker at all
        shutil.copy(frame["exr"], frames / f"f{k:03d}.exr")
    status, stdout, _ = _run(capsys, "--depth", frames, "--fov", 40, *_blender_args(frame),
                             "--radius", RADIUS, "--out", tmp_path / "vo")
    assert status == 0
    written = sorted(p.name for p in (tmp_path / "vo").iterdir())
    assert written == ["f000_line-9.exr", "f001_line-9.exr", "f002_line-9.exr"]
    assert "flicker: mean |V(t+1) - V(t)| = 0.00000" in stdout
    status, stdout, _ = _run(capsys, "--depth", frames, "--fov", 40, *_blender_args(frame), "--radius", RADIUS,
                             "--flicker-reference", 64, "--out", tmp_path / "vo2")
    assert status == 0 and "flicker: 0.00000 (mean |V(t+1) - V(t)| = 0.00000 less the reference's 0.00000" in stdout
    # a glob and a {stem} pattern; another frame makes the change non-zero
    shutil.copy(frame["exr"], tmp_path / "g0.exr")
    vio.write_gbuffer(tmp_path / "g1.exr", frame["gb"], world_normals=True)  # inf background
    arr = vio.exr_channels(tmp_path / "g1.exr")
    status, stdout, err = _run(capsys, "--depth", tmp_path / "g*.exr", "--fov", 40, "--pose", frame["pose"],
                               "--normal-space", "world", "--background", "1e10", "--radius", RADIUS,
                               "--seed", 3, "--out", tmp_path / "out" / "{stem}.png")
    assert status == 0, err
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["g0.png", "g1.png"]
    assert "flicker" in stdout and "View Layer.Depth.Z" in arr


@pytest.mark.parametrize("argv, message", [
    (["--depth", "{missing}", "--fov", "40"], "no such file"),
    (["--depth", "{exr}", "--fov", "40", "--method", "ray:3"], "unknown method 'ray'"),
    (["--depth", "{exr}", "--fov", "40", "--method", "line:9,point:12"], "--method takes one configuration"),
    (["--depth", "{exr}", "--fov", "40", "--method", "hegeman"], "needs the scene's description"),
    (["--depth", "{exr}", "--fov", "40", "--depth-channel", "nope"],
     "no depth channel 'nope'; the file has the channels View Layer.Depth.Z, View Layer.Normal.X"),
    (["--depth", "{exr}", "--fov", "40", "--normal", "{missing}"], "no such file"),
    (["--depth", "{exr}", "--fov", "40", "--normal-space", "world"], "needs the camera's --pose"),
    (["--depth", "{exr}", "--fov", "40", "--pose", "{exr}"], "--pose"),
    (["--depth", "{exr}", "--fov", "400"], "fov_y"),
    (["--depth", "{dir}/*.nothing", "--fov", "40"], "matches no file"),
])
def test_inconsistent_inputs_exit_2_with_a_message(frame, tmp_path, capsys, argv, message):
    argv = [a.format(missing=tmp_path / "missing.exr", exr=frame["exr"], dir=frame["dir"]) for a in argv]
    status, stdout, err = _run(capsys, *argv, "--radius", RADIUS, "--out", tmp_path / "vo.exr")
    assert status == 2
    assert err.startswith("vobscure estimate: error: ") and message in err, err
    assert not (tmp_path / "vo.exr").exists()


@pytest.mark.parametrize("argv, message", [
    (["--radius", "0.5"], "one of the arguments --fov --intrinsics --projection is required"),
    (["--fov", "40", "--intrinsics", "1", "1", "1", "1", "--radius", "0.5"], "not allowed with argument"),
    (["--fov", "40"], "the following arguments are required: --radius"),
])
def test_camera_and_required_arguments(frame, tmp_path, capsys, argv, message):
    with pytest.raises(SystemExit) as exc:
        cli.main(["estimate", "--depth", str(frame["exr"]), *argv, "--out", str(tmp_path / "vo.exr")])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "vobscure estimate: error: " in err and message in err


def test_out_must_fit_the_frames(frame, tmp_path, capsys):
    status, _, err = _run(capsys, "--depth", frame["exr"], "--fov", 40, "--radius", RADIUS, "--out",
                          tmp_path / "vo.tiff")
    assert status == 2 and "the suffix must be .exr, .png, .npy or .pfm" in err
    status, _, err = _run(capsys, "--depth", frame["exr"], "--fov", 40, "--radius", RADIUS, "--out", frame["exr"])
    assert status == 2 and "would overwrite the input frame" in err


def test_channels_named_on_the_command_line(frame, tmp_path, capsys):
    names = ",".join(f"View Layer.Normal.{a}" for a in "XYZ")
    status, _, err = _run(capsys, "--depth", frame["exr"], "--fov", frame["gb"].camera.fov_y,
                          *_blender_args(frame), "--depth-channel", "View Layer.Depth.Z",
                          "--normal-channels", names, "--radius", RADIUS, "--quiet", "--out", tmp_path / "v.npy")
    assert status == 0, err
    np.testing.assert_allclose(np.load(tmp_path / "v.npy"), _expected(frame["gb"]), atol=TOL)


# --------------------------------------------------------------------------- Blender 5's own files
def test_blender_single_layer_files_by_default(tmp_path, capsys):
    """The File Output node's two single-layer files (depth as R = G = B, normals as X/Y/Z),
    nothing named: the channels used and the conversion counts are printed, one line each,
    and the output is named after the frame (frameDepth.exr -> frame_gtao.exr)."""
    np.savetxt(tmp_path / "pose.txt", blender_frames.pose())
    d = blender_frames.DIR / "single"
    status, stdout, err = _run(capsys, "--depth", d / "frameDepth.exr", "--normal", d / "frameNormal.exr",
                               "--fov", blender_frames.record()["camera"]["fov_y_degrees"],
                               "--pose", tmp_path / "pose.txt", "--normal-space", "world", "--background", "1e10",
                               "--radius", RADIUS, "--method", "gtao", "--out", tmp_path / "vo")
    assert status == 0, err
    assert err == ""
    lines = stdout.splitlines()
    assert f"  depth: {d / 'frameDepth.exr'}, channel R (R = G = B: a grey image, as Blender's single-layer " \
           "File Output writes a float)" in lines
    assert f"  normals: {d / 'frameNormal.exr'}, channels X, Y, Z" in lines
    gb = vo.render_gbuffer(blender_frames.scene(), blender_frames.camera())
    covered, background = int(gb.valid.sum()), int((~gb.valid).sum())
    assert f"  background pixels: {background} of 768 pixels (no surface: depth not finite or >= 1e+10)" in lines
    for label in ("renormalized", "flipped", "repaired"):
        assert any(line.startswith(f"  {label} normals: 0 of {covered} covered pixels") for line in lines), label
    assert sorted(p.name for p in (tmp_path / "vo").iterdir()) == ["frame_gtao.exr"]
    # the same as the library on the same files
    cam = blender_frames.camera()
    frame = vio.read_gbuffer((d / "frameDepth.exr", d / "frameNormal.exr"), camera=cam, normal_space="world",
                             background=1e10)
    expected = vo.methods.parse("gtao")[0].run(frame, radius=RADIUS, seed=0)
    got = vio.exr_channels(tmp_path / "vo" / "frame_gtao.exr")["Y"]
    np.testing.assert_array_equal(np.isnan(got), ~gb.valid)
    assert np.nanmax(np.abs(got - expected)) <= TOL


def test_conversion_counts_replace_the_warnings(frame, tmp_path, capsys):
    """Known numbers of long, backward and zero normals: counted in one line each; no Python
    warning (pytest turns one into an error)."""
    gb = frame["gb"]
    idx = np.flatnonzero(gb.valid)
    normals = gb.world_normal.reshape(-1, 3).astype(np.float32).copy()
    long, backward, zero = idx[:5], idx[5:12], idx[12:15]
    normals[long] *= 1.5
    normals[backward] *= -1.0
    normals[zero] = 0.0
    normals = normals.reshape(gb.shape + (3,))
    channels = {"Depth.V": np.where(gb.valid, gb.depth, 1e10).astype(np.float32)}
    channels.update({f"Normal.{a}": np.ascontiguousarray(normals[:, :, k]) for k, a in enumerate("XYZ")})
    import OpenEXR

    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
                 channels).write(str(tmp_path / "shot_depth_0007.exr"))
    argv = ["--depth", tmp_path / "shot_depth_0007.exr", "--fov", gb.camera.fov_y, *_blender_args(frame),
            "--radius", RADIUS, "--out", tmp_path / "out"]
    status, _, err = _run(capsys, *argv)
    assert status == 2 and "3 zero or NaN vector(s) on covered pixels" in err
    status, stdout, err = _run(capsys, *argv, "--repair-normals")
    assert status == 0, err
    covered = int(gb.valid.sum())
    assert f"  renormalized normals: 5 of {covered} covered pixels" in stdout
    assert f"  flipped normals: 7 of {covered} covered pixels" in stdout
    assert f"  repaired normals: 3 of {covered} covered pixels" in stdout
    assert "Warning" not in stdout + err
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["shot_0007_line-9.exr"]


def test_help_lists_the_methods(capsys):
    with pytest.raises(SystemExit) as exc:
        cli.main(["estimate", "--help"])
    assert exc.value.code == 0
    text = capsys.readouterr().out
    screen = [n for n in vo.methods.names() if not vo.methods.get(n).needs_scene]
    assert f"NAME one of {', '.join(screen)}" in " ".join(text.split())
    for name in vo.methods.names():
        assert f"\n  {name} (" in text


def test_outputs_are_named_after_the_frame(frame, tmp_path, capsys):
    frames = tmp_path / "frames"
    frames.mkdir()
    for name in ("Depth0001.exr", "Depth0002.exr"):
        shutil.copy(frame["exr"], frames / name)
    status, _, err = _run(capsys, "--depth", frames, "--fov", 40, *_blender_args(frame), "--radius", RADIUS,
                          "--method", "point:12", "--quiet", "--out", tmp_path / "a")
    assert status == 0, err
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == ["frame0001_point-12.exr", "frame0002_point-12.exr"]
    status, _, err = _run(capsys, "--depth", frames, "--fov", 40, *_blender_args(frame), "--radius", RADIUS,
                          "--quiet", "--out", tmp_path / "b" / "{frame}_{method}_{stem}.png")
    assert status == 0, err
    assert sorted(p.name for p in (tmp_path / "b").iterdir()) == ["frame0001_line-9_Depth0001.png",
                                                                  "frame0002_line-9_Depth0002.png"]


def test_a_truncated_or_wrong_file_is_named(tmp_path, capsys):
    data = (blender_frames.DIR / "render" / "frame.exr").read_bytes()
    (tmp_path / "cut.exr").write_bytes(data[: len(data) // 2])
    status, _, err = _run(capsys, "--depth", tmp_path / "cut.exr", "--fov", 50, "--radius", RADIUS,
                          "--out", tmp_path / "vo.exr")
    assert status == 2 and f"not a readable EXR file: {tmp_path / 'cut.exr'} (" in err
    normal = blender_frames.DIR / "single" / "frameNormal.exr"
    status, _, err = _run(capsys, "--depth", normal, "--fov", 50, "--radius", RADIUS, "--out", tmp_path / "vo.exr")
    assert status == 2 and f"{normal}: no depth channel" in err and "the file has the channels A, X, Y, Z" in err
    assert not (tmp_path / "vo.exr").exists()
