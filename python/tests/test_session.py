"""svbtdf.Session and svbtdf.SliceStore against the files they read."""

import json
import os
import re
import shutil

import numpy as np
import pytest

import svbtdf


def test_session_manifest_plan_journal_and_images(tiny):
    session = svbtdf.Session.open(tiny.session)
    with open(os.path.join(tiny.session, "session.json")) as f:
        assert session.manifest == json.load(f)
    assert session.rig == session.manifest["rig"]
    assert len(session.plan) == len(session.journal) and session.plan[0] in session
    assert {e["key"] for e in session.journal} == set(session.plan)
    dot = next(k for k in session.plan if k.startswith("dot/"))
    image = session.image(dot, check_crc=True)
    assert image.dtype == np.uint16 and image.ndim in (2, 3) and image.max() > 0
    camera = session.rig["camera"]
    channels = camera.get("channels", 1)
    assert image.shape == ((camera["height"], camera["width"]) + ((channels,) if channels > 1 else ()))
    assert session.verify() == {"complete": True, "missing": [], "corrupt": [], "duplicated": [], "unexpected": [],
                                "summary": session.verify()["summary"]}
    with pytest.raises(svbtdf.Error, match="dot/q9999"):
        session.image("dot/q9999/e0/r0")


def test_verify_reports_a_damaged_image(tiny, tmp_path):
    copy = tmp_path / "session"
    shutil.copytree(tiny.session, copy)
    session = svbtdf.Session.open(str(copy))
    key = session.plan[-1]
    entry = next(e for e in session.journal if e["key"] == key)
    with open(copy / entry["file"], "r+b") as f:
        f.truncate(entry["bytes"] // 2)
    report = session.verify(check_crc=False)
    assert not report["complete"] and report["corrupt"] == [key]
    with pytest.raises(svbtdf.Error, match=re.escape(entry["file"].split("/")[-1])):
        session.image(key)


def test_an_unreadable_session_names_its_file(tmp_path):
    (tmp_path / "session.json").write_text("{ not json")
    with pytest.raises(svbtdf.FormatError, match=re.escape(str(tmp_path / "session.json"))):
        svbtdf.Session.open(str(tmp_path))


def test_slice_store_samples_and_maps(tiny):
    store = svbtdf.SliceStore.open(tiny.processed)
    material = svbtdf.Material.load(tiny.material)
    info = store.info
    assert (info["texels_x"], info["texels_y"]) == (material.width, material.height)
    assert store.rho_d.shape == (info["texels_y"], info["texels_x"], 3) and store.rho_d.dtype == np.float32
    assert store.mask.shape == store.reach.shape == (info["texels_y"], info["texels_x"])
    # The flat white frame's noise per channel (docs/slice-store.md): a fraction of a percent here.
    assert len(info["white_exitance_noise"]) == 3 and all(0.0 < v < 0.01 for v in info["white_exitance_noise"])
    # The material's rho_d is the store's (fit takes it as measured).
    np.testing.assert_array_equal(material.rho_d, store.rho_d)

    held_out = material.provenance["holdout"]["dots"]
    s = store.samples(2, 1, held_out_dots=held_out)
    q = info["num_dots"]
    assert s["light"].shape == (q, 3) and s["values"].shape == (q, 3) and s["values"].dtype == np.float32
    assert (s["light"][:, 2] < 0).all() and s["view"][2] > 0
    np.testing.assert_allclose(np.linalg.norm(s["light"], axis=1), 1.0)
    assert list(np.flatnonzero(s["held_out"])) == held_out
    assert s["valid"].sum() > q // 2
    np.testing.assert_array_equal(s["valid"], np.isfinite(s["values"]).all(axis=1))
    # The fit's own choice of held-out dots, recomputed from its options, is the recorded one.
    fraction, seed = material.provenance["holdout"]["fraction"], material.provenance["holdout"]["seed"]
    np.testing.assert_array_equal(store.samples(2, 1, holdout=fraction, seed=seed)["held_out"], s["held_out"])
    assert store.slice(2, 1).shape == (svbtdf.hemicube_cells(info["light_resolution"])[1].size,)
    with pytest.raises(svbtdf.InvalidInputError, match="outside"):
        store.samples(info["texels_x"], 0)
