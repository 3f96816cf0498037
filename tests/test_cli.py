"""The `vobscure` command: outputs, provenance, atomic writes, errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

import vobscure as vo
from vobscure import _io, cli


def test_render_writes_images_and_npz(tmp_path, capsys):
    status = cli.main(["render", "--scene", "crease", "--size", "24", "16", "--rays", "32",
                       "--radius", "0.5", "--seed", "3", "--out", str(tmp_path), "--quiet"])
    assert status == 0
    names = sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith("."))
    assert names == ["crease_ao.npz", "crease_ao_depth.png", "crease_ao_normal.png", "crease_ao_visibility.png"]
    # beside them only the set's manifest and the folder's lock (vobscure._io.file_set)
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == [".crease_ao.files.json",
                                                                                    ".vobscure.lock"]
    with np.load(tmp_path / "crease_ao.npz") as data:
        prov = json.loads(str(data["provenance"]))
        vis, valid, depth = data["visibility"], data["valid"], data["depth"]
    assert prov["scene"] == "crease" and prov["seed"] == 3 and prov["radius"] == 0.5
    assert prov["camera"]["size"] == [24, 16] and prov["version"] == vo.__version__
    assert prov["seconds"] > 0
    assert vis.shape == (16, 24) and np.array_equal(np.isnan(vis), ~valid)
    assert np.all(np.isposinf(depth[~valid]))
    # the same job through the API gives the same numbers
    scene = vo.scenes.crease()
    gb = vo.render_gbuffer(scene, vo.Camera.from_dict(prov["camera"]))
    ref = vo.ground_truth(scene, gb, radius=0.5, rays=32, seed=3, progress=False)
    np.testing.assert_array_equal(ref.value, vis)


def test_scenes_lists_registry(capsys):
    assert cli.main(["scenes"]) == 0
    out = capsys.readouterr().out
    for name in vo.scenes.names():
        assert name in out


def test_compare_help_and_choices_come_from_the_registries(capsys):
    """``--reference`` accepts the reference registry's names and ``--help`` lists every
    reference and method with its summary; a name outside the registry is refused."""
    from vobscure import methods, references

    with pytest.raises(SystemExit):
        cli.main(["compare", "--help"])
    out = " ".join(capsys.readouterr().out.split())        # argparse wraps lines
    for ref in references.REFERENCES.values():
        assert f"{ref.name}: {' '.join(ref.summary.split())}" in out
    for name in methods.names():
        assert f"{name} (" in out
    with pytest.raises(SystemExit):
        cli.main(["compare", "--reference", "fog"])
    err = capsys.readouterr().err
    assert "invalid choice: 'fog'" in err and "sky_uniform" in err


def test_bad_scene_is_a_clean_error(tmp_path, capsys):
    assert cli.main(["render", "--scene", "nosuchscene", "--out", str(tmp_path), "--quiet"]) == 2
    assert "nosuchscene" in capsys.readouterr().err
    assert cli.main(["render", "--scene", str(tmp_path / "missing.obj"), "--quiet"]) == 2
    assert cli.main(["render", "--scene", "slab", "--rays", "1", "--quiet", "--out", str(tmp_path)]) == 2
    assert "rays" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_atomic_write_keeps_the_good_file(tmp_path):
    target = tmp_path / "result.npz"
    _io.save_npz(target, {"run": 1}, x=np.arange(3))
    good = target.read_bytes()

    def interrupted(fh):
        fh.write(b"partial")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        _io.atomic_write(target, interrupted)
    assert target.read_bytes() == good
    assert [p.name for p in tmp_path.iterdir()] == ["result.npz"]  # no temporary left behind


def test_open_mesh_volumetric_needs_the_flag(tmp_path, capsys):
    import trimesh

    box = trimesh.creation.box()
    box.update_faces(np.arange(len(box.faces)) != 0)  # a hole
    path = tmp_path / "open.stl"
    box.export(path)
    args = ["render", "--scene", str(path), "--quantity", "volumetric", "--size", "8", "8",
            "--samples", "32", "--radius", "0.3", "--quiet", "--out", str(tmp_path / "out")]
    assert cli.main(args) == 2
    assert "--allow-open" in capsys.readouterr().err
    assert cli.main(args + ["--allow-open"]) == 0
    with np.load(tmp_path / "out" / "open_volumetric.npz") as data:
        assert json.loads(str(data["provenance"]))["allow_open"] is True


def test_figures_command_lists_and_rejects_unknown_names(capsys, tmp_path):
    from vobscure.cli import main
    from vobscure.experiments import figures

    assert main(["figures", "--list"]) == 0
    listed = capsys.readouterr().out.split()
    assert "conventions" in listed and listed == figures.names()
    assert main(["figures", "no_such_figure", "--out", str(tmp_path)]) == 2
    assert "no_such_figure" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_figures_command_runs_one_figure_quick(capsys, tmp_path):
    from vobscure.cli import main

    assert main(["figures", "conventions", "--quick", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "conventions.png").is_file()
    assert "conventions.png" in capsys.readouterr().out


def test_camera_takes_negative_coordinates_as_written(tmp_path):
    """``--camera -1.5,2,...`` (a value starting with a minus sign) is the camera's value, not
    an unknown option; the run's provenance records that eye."""
    status = cli.main(["compare", "--camera", "-1.5,2,1.5,0,0,0,40", "--scene", "slab", "--size", "16", "12",
                       "--methods", "line:5", "--reference", "screen", "--quick", "--quiet",
                       "--out", str(tmp_path / "out"), "--cache", str(tmp_path / "cache")])
    assert status == 0
    prov = json.loads((tmp_path / "out" / "provenance.json").read_text())
    assert prov["camera"]["eye"] == [-1.5, 2.0, 1.5] and prov["camera"]["fov_y"] == 40.0


def test_camera_with_a_negative_first_number_and_too_few_values_is_a_clean_error(tmp_path, capsys):
    assert cli.main(["compare", "--camera", "-1,2,3", "--out", str(tmp_path)]) == 2
    assert "6 or 7 numbers" in capsys.readouterr().err


def _compare_slab(tmp_path, *view):
    return cli.main(["compare", "--scene", "slab", "--size", "16", "12", *view, "--methods", "line:5",
                     "--reference", "screen", "--quick", "--out", str(tmp_path / "out"),
                     "--cache", str(tmp_path / "cache")])


def test_eye_target_fov_take_negative_numbers_as_written(tmp_path, capsys):
    """``--eye -1.5 2 -1e-1`` (plain and exponent negatives) is the eye; the run records the
    camera and how the default radius was chosen, and prints it."""
    status = _compare_slab(tmp_path, "--eye", "-1.5", "2", "-1e-1", "--target", "0", "-0.25", "0", "--fov", "40")
    assert status == 0
    prov = json.loads((tmp_path / "out" / "provenance.json").read_text())
    assert prov["camera"]["eye"] == [-1.5, 2.0, -0.1] and prov["camera"]["target"] == [0.0, -0.25, 0.0]
    assert prov["camera"]["fov_y"] == 40.0
    rule = prov["radius_rule"]
    assert rule["radius"] == prov["radii"][0] and rule["rule"] in ("extent", "extent+cap")
    assert rule["sentence"] in capsys.readouterr().out


def test_fov_alone_keeps_the_scenes_eye_and_target(tmp_path):
    assert _compare_slab(tmp_path, "--fov", "30", "--radius", "0.2") == 0
    prov = json.loads((tmp_path / "out" / "provenance.json").read_text())
    view = vo.scenes.slab().view
    assert prov["camera"]["eye"] == list(view["eye"]) and prov["camera"]["fov_y"] == 30.0
    assert prov["radius_rule"] is None and prov["radii"] == [0.2]       # --radius given: no rule


def test_render_takes_eye_target_up(tmp_path):
    status = cli.main(["render", "--scene", "slab", "--size", "12", "8", "--rays", "4", "--eye", "-2", "3", "-2",
                       "--target", "0", "0", "0", "--up", "0", "1", "0", "--fov", "35", "--out", str(tmp_path),
                       "--quiet"])
    assert status == 0
    with np.load(tmp_path / "slab_ao.npz") as data:
        prov = json.loads(str(data["provenance"]))
    assert prov["camera"]["eye"] == [-2.0, 3.0, -2.0] and prov["camera"]["fov_y"] == 35.0


@pytest.mark.parametrize("args, message", [
    (["--eye", "0", "0", "0", "--target", "0", "0", "0"], "eye and target must be distinct"),
    (["--fov", "180"], "--fov must be a vertical field of view in degrees in (0, 180)"),
    (["--eye", "nan", "1", "1"], "--eye must be three finite numbers"),
    (["--camera", "1,2,3,0,0,0", "--eye", "1", "2", "3"], "either as --camera or as --eye"),
])
def test_bad_view_options_are_clean_errors(tmp_path, capsys, args, message):
    assert _compare_slab(tmp_path, *args) == 2
    assert message in capsys.readouterr().err


def test_eye_with_too_few_numbers_is_an_argparse_error(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        _compare_slab(tmp_path, "--eye", "-1", "2", "--target", "0", "0", "0")
    assert exc.value.code == 2 and "--eye: expected 3 arguments" in capsys.readouterr().err


def test_gbuffer_with_eye_is_a_clean_error(tmp_path, capsys):
    path = tmp_path / "depth.npy"
    np.save(path, np.ones((4, 4)))
    assert cli.main(["compare", "--gbuffer", str(path), "--fov", "40", "--eye", "0", "0", "1",
                     "--out", str(tmp_path)]) == 2
    assert "--gbuffer brings its own view" in capsys.readouterr().err


def test_compare_thickness_layers_parses_and_runs(tmp_path):
    args = cli._parser().parse_args(["compare", "--thickness", "layers", "--layers", "2"])
    assert (args.thickness, args.layers) == ("layers", 2)
    args = cli._parser().parse_args(["compare", "--thickness", "0.25"])
    assert (args.thickness, args.layers) == (0.25, None)
    out = tmp_path / "out"
    assert cli.main(["compare", "--scene", "thin_occluders", "--size", "12", "12", "--methods", "line:5,area:1",
                     "--thickness", "layers", "--layers", "2", "--reference", "screen", "--quick", "--no-cache",
                     "--no-suggest", "--out", str(out), "--quiet"]) == 0
    prov = json.loads((out / "provenance.json").read_text())
    assert prov["thickness"] == "layers" and prov["layers"] == 2
    assert "G-buffer with 2 layers" in [s["stage"] for s in prov["stages"]]


@pytest.mark.parametrize("args, message", [
    (["--thickness", "fat"], "argument --thickness: must be a positive number (the thickness model, world units) "
                             "or 'layers'"),
    (["--thickness", "-0.5"], "argument --thickness: must be a positive number"),
    (["--thickness", "layers", "--layers", "0"], "argument --layers: must be an integer >= 2"),
    (["--thickness", "layers", "--layers", "two"], "argument --layers: must be an integer >= 2"),
])
def test_compare_bad_thickness_or_layers_is_an_argparse_error(tmp_path, capsys, args, message):
    with pytest.raises(SystemExit) as exc:
        cli.main(["compare", "--scene", "slab", "--out", str(tmp_path), "--quiet", *args])
    assert exc.value.code == 2 and message in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_compare_layers_without_thickness_layers_is_a_clean_error(tmp_path, capsys):
    assert cli.main(["compare", "--scene", "slab", "--size", "8", "8", "--layers", "3", "--out", str(tmp_path),
                     "--quiet"]) == 2
    assert "give thickness='layers' (--thickness layers)" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())
