"""The pipeline's stages as functions: same results as the command line, progress, Ctrl-C."""

import fcntl
import json
import os
import re
import shutil
import signal
import time

import numpy as np
import pytest

import svbtdf
from conftest import svbtdf_cli


def test_compare_equals_svbtdf_compare_json(tiny, tmp_path):
    json_path = tmp_path / "compare.json"
    svbtdf_cli("compare", tiny.material, tiny.truth, "--json", json_path)
    metrics = svbtdf.compare(tiny.material, tiny.truth)
    assert metrics == json.loads(json_path.read_text())
    assert metrics["texels_compared"] > 0 and metrics["heldout_rel_rmse"] > 0


def test_fit_reports_progress_stops_on_ctrl_c_and_resumes(tiny, tmp_path):
    out = str(tmp_path / "material")
    options = dict(representatives=0.02, threads=1, seed=2)
    reported, lines = [], []

    def interrupt_after_two_fits(label, done, total):
        # One Ctrl-C: a second one stops the process at once, as on the command line. The "fit"
        # bar counts the representatives; the clustering's bar ("cluster") comes before it.
        if label == "fit" and done >= 2 and not any(l == "fit" and d >= 2 for l, d, _ in reported):
            os.kill(os.getpid(), signal.SIGINT)
        reported.append((label, done, total))

    with pytest.raises(svbtdf.Interrupted, match="interrupted") as info:
        svbtdf.fit(tiny.processed, out, progress=interrupt_after_two_fits, **options)
    assert isinstance(info.value, KeyboardInterrupt)
    with pytest.raises(KeyboardInterrupt) as python_interrupt:  # Python's own handler is back
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(5)
    assert not isinstance(python_interrupt.value, svbtdf.Error)
    assert reported and all(total > 0 and 0 <= done <= total for _, done, total in reported)
    assert not os.path.exists(out) and os.path.exists(out + ".partial-fits.jsonl")

    def refuse(label, done, total):
        raise RuntimeError("stopped by the callback")

    with pytest.raises(RuntimeError, match="stopped by the callback"):
        svbtdf.fit(tiny.processed, out, progress=refuse, **options)

    result = svbtdf.fit(tiny.processed, out, log=lines.append, **options)
    assert result["material"] == out and isinstance(result["warnings"], list)
    statistics = svbtdf.Material.load(out).provenance["statistics"]
    assert statistics["resumed_fits"] >= 2
    assert any(line.startswith("fitted dual-microfacet") for line in lines)
    assert not os.path.exists(out + ".partial-fits.jsonl")

    with pytest.raises(svbtdf.InvalidInputError, match="exists and is not empty"):
        svbtdf.fit(tiny.processed, out, **options)
    with pytest.raises(svbtdf.InvalidInputError, match="representatives: must be a fraction"):
        svbtdf.fit(tiny.processed, str(tmp_path / "other"), representatives=2)


def test_render_is_an_image_of_the_documented_shape_and_deterministic(tiny, tmp_path):
    options = dict(view_deg=(25, 180), resolution=(24, 16), spp=4, seed=3)
    image = svbtdf.render(tiny.material, out=str(tmp_path / "image.exr"), **options)
    assert image.shape == (16, 24, 3) and image.dtype == np.float32
    assert np.isfinite(image).all() and image.mean() > 0
    assert os.path.getsize(tmp_path / "image.exr") > 0
    np.testing.assert_array_equal(svbtdf.render(tiny.material, threads=1, **options), image)
    with pytest.raises(svbtdf.InvalidInputError, match="--scene"):
        svbtdf.render(tiny.material, scene="studio", **options)


def test_calibrate_process_and_run_equal_the_command_line(tiny, tmp_path):
    session = str(tmp_path / "session")
    shutil.copytree(tiny.session, session, ignore=shutil.ignore_patterns("calibration.json"))
    with pytest.raises(svbtdf.InvalidInputError, match=re.escape(session) + ": has no calibration.json"):
        svbtdf.process(session, str(tmp_path / "early"))

    calibrated = svbtdf.calibrate(session)
    assert calibrated["file"] == os.path.join(session, "calibration.json")
    with open(calibrated["file"]) as f:
        assert calibrated["calibration"] == json.load(f)
    with open(os.path.join(tiny.session, "calibration.json")) as f:
        by_cli = json.load(f)
    # `svbtdf run` calibrated the same, to the last digits the solvers' threads leave open.
    for key in ("fx", "fy", "cx", "cy", "distortion", "rms_px"):
        assert calibrated["calibration"]["camera"][key] == pytest.approx(by_cli["camera"][key], rel=1e-8, abs=1e-12), key

    reported = []
    work = tmp_path / "work"
    work.mkdir()  # process, like `svbtdf process`, creates its store but not the folders above it
    processed = svbtdf.process(session, str(work / "processed"), progress=lambda *p: reported.append(p))
    assert processed["texels"] == processed["valid_texels"] > 0 and processed["dots"] > 0
    assert reported and reported[-1][1] == reported[-1][2]  # the last report is the finished bar
    store, cli_store = svbtdf.SliceStore.open(processed["store"]), svbtdf.SliceStore.open(tiny.processed)
    # Samples are stored as float16: a calibration differing in its 12th digit may round one the
    # other way (2^-11 relative).
    np.testing.assert_allclose(store.rho_d, cli_store.rho_d, rtol=1e-3)
    np.testing.assert_allclose(store.samples(4, 4)["values"], cli_store.samples(4, 4)["values"], rtol=1e-3)

    lines = []
    result = svbtdf.run(session, str(tmp_path / "material"), work=str(work), representatives=0.02, log=lines.append)
    assert result["work"] == str(work)
    assert "== 2/3 processing: using " + str(work / "processed") in lines
    assert svbtdf.Material.load(result["material"]).width == store.info["texels_x"]


def test_a_stage_refuses_an_output_folder_another_writer_holds(tiny, tmp_path):
    out = tmp_path / "locked"
    with open(tmp_path / ".locked.lock", "w") as held:  # common/folder_lock.h: PARENT/.NAME.lock
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        with pytest.raises(svbtdf.IoError, match=re.escape(str(out))):
            svbtdf.fit(tiny.processed, str(out), representatives=0.02)
    assert not out.exists()


def test_fit_model_slab_writes_both_interfaces_and_evaluates_as_the_command_line(tiny, tmp_path):
    out = str(tmp_path / "slab")
    svbtdf.fit(tiny.processed, out, model="slab", representatives=0.05)
    material = svbtdf.Material.load(out)
    assert material.btdf == "slab"
    for name in ("slab_entry_alpha_x", "slab_entry_alpha_y", "slab_entry_azimuth", "slab_exit_alpha_x", "slab_exit_alpha_y",
                 "slab_exit_azimuth", "slab_entry_roughness_se", "slab_exit_roughness_se", "slab_internal_reflection",
                 "slab_longer_paths"):
        array = getattr(material, name)
        assert array.shape == (material.height, material.width) and array.dtype == np.float32, name
    assert (material.slab_entry_alpha_y > 0).all() and (material.slab_exit_alpha_y > 0).all()
    assert (material.slab_entry_alpha_x >= material.slab_entry_alpha_y).all()
    assert material.baseline_alpha_x is None
    wi, wo = np.array([0.0, 0.3, -1.0]), np.array([0.0, -0.7, 0.7])
    value = material.eval(np.array([2, 3]), wi, wo)
    cli = json.loads(svbtdf_cli("eval", out, "--texel", "2", "3", "--wi", "0", "0.3", "-1", "--wo", "0", "-0.7", "0.7",
                                "--json").stdout)
    np.testing.assert_allclose(value.reshape(-1), cli["rgb"], rtol=1e-12)
    with pytest.raises(svbtdf.InvalidInputError, match="must be 'dual', 'ggx' or 'slab'"):
        svbtdf.fit(tiny.processed, str(tmp_path / "other"), model="walter")
