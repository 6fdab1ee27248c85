"""svbtdf.Material against the command line: values, shapes, errors, and the renderer's BSDF."""

import json
import os
import re
import shutil

import numpy as np
import pytest

import svbtdf


@pytest.fixture(scope="module")
def material(tiny):
    return svbtdf.Material.load(tiny.material)


def random_directions(rng, n):
    """Light directions below the sample (z < 0) and views above it, unnormalised."""
    wi = rng.normal(size=(n, 3))
    wi[:, 2] = -np.abs(wi[:, 2]) - 0.05
    wo = rng.normal(size=(n, 3))
    wo[:, 2] = np.abs(wo[:, 2]) + 0.05
    return wi, wo


def test_maps_have_the_documented_shapes_and_dtypes(material):
    h, w = material.height, material.width
    for name, shape in [("alpha", (h, w)), ("shadowing_roughness", (h, w)), ("k_s", (h, w, 3)), ("rho_d", (h, w, 3)),
                        ("residual", (h, w)), ("cluster", (h, w))]:
        array = getattr(material, name)
        assert array.dtype == np.float32, name
        assert array.shape == shape, name
    assert material.weight_index.shape[:2] == (h, w) and material.weight_index.shape == material.weight_value.shape
    np.testing.assert_allclose(material.weight_value.sum(axis=2), 1.0, atol=1e-4)  # float32 affine weights
    assert material.baseline_alpha_x is None  # a dual-microfacet material
    assert material.representative_texels.dtype == np.int64
    assert material.btdf == "dual-microfacet"
    # Representatives are fitted on their own samples: residual >= 0 there.
    reps = material.representative_texels
    assert (material.residual.reshape(-1)[reps] >= 0).all()


def test_eval_equals_svbtdf_eval(tiny, material):
    rng = np.random.default_rng(3)
    wi, wo = random_directions(rng, 6)
    texels = np.stack([rng.integers(0, material.width, 6), rng.integers(0, material.height, 6)], axis=1)
    values = material.eval(texels, wi, wo)
    assert values.shape == (6, 3) and values.dtype == np.float64
    for k in range(6):
        cli = tiny.cli_eval(texels[k, 0], texels[k, 1], [repr(v) for v in wi[k]], [repr(v) for v in wo[k]])
        np.testing.assert_allclose(values[k], cli["rgb"], rtol=1e-12, atol=0)
        assert values[k].min() > 0  # R > 0: the test compares real values, not zeros


def test_eval_broadcasts_one_texel_and_one_direction(material):
    rng = np.random.default_rng(4)
    wi, wo = random_directions(rng, 50)
    all_pairs = material.eval(np.tile([1, 2], (50, 1)), wi, wo)
    np.testing.assert_array_equal(material.eval([1, 2], wi, wo), all_pairs)
    np.testing.assert_array_equal(material.eval([1, 2], wi[7], wo)[7], all_pairs[7])
    # The same on one thread: the parallel loop changes nothing.
    np.testing.assert_array_equal(material.eval([1, 2], wi, wo, threads=1), all_pairs)


def test_bad_input_raises_the_documented_exceptions(tiny, material):
    with pytest.raises(svbtdf.InvalidInputError, match=r"texel: \(%d, 0\) is outside" % material.width) as info:
        material.eval([material.width, 0], [0, 0, -1], [0, 0, 1])
    assert info.value.kind == "invalid_input" and info.value.subject == "texel"
    assert isinstance(info.value, svbtdf.Error) and isinstance(info.value, ValueError)
    with pytest.raises(svbtdf.InvalidInputError, match=r"wi\[1\]: must point toward the light"):
        material.eval([0, 0], [[0, 0, -1], [0, 0, 1]], [0, 0, 1])
    many = np.tile([0.1, 0.2, -1.0], (20000, 1))
    many[[15000, 9000], 2] = 0.0
    with pytest.raises(svbtdf.InvalidInputError, match=r"wi\[9000\]: must point toward the light"):
        material.eval([0, 0], many, [0, 0, 1])  # the first bad row, whichever thread met it
    with pytest.raises(svbtdf.InvalidInputError, match=r"wo\[0\]: must not lie in the sample's plane"):
        material.pdf([0, 0], [0, 0, -1], [1, 0, 0])
    with pytest.raises(svbtdf.InvalidInputError, match="shape"):
        material.eval([0, 0], [0, -1], [0, 0, 1])
    with pytest.raises(svbtdf.InvalidInputError, match="different lengths"):
        material.eval([[0, 0], [1, 1]], np.tile([0, 0, -1.0], (3, 1)), [0, 0, 1])
    with pytest.raises(svbtdf.InvalidInputError, match=r"u\[0\]: must lie in \[0, 1\)"):
        material.sample([0, 0], [0, 0, 1], [0.5, 0.5, 1.0])
    with pytest.raises(svbtdf.Error, match="material.json"):
        svbtdf.Material.load(os.path.join(tiny.root, "no-such-material"))


def test_a_damaged_manifest_is_a_format_error_naming_the_file(tiny, tmp_path):
    damaged = tmp_path / "damaged"
    shutil.copytree(tiny.material, damaged)
    manifest = json.loads((damaged / "material.json").read_text())
    manifest["version"] = 99
    (damaged / "material.json").write_text(json.dumps(manifest))
    with pytest.raises(svbtdf.FormatError, match=re.escape(str(damaged / "material.json") + ": has material format version 99")):
        svbtdf.Material.load(str(damaged))


def test_the_texel_ndf_is_normalised_on_the_hemicube(material):
    directions, solid_angles = svbtdf.hemicube_cells(material.ndf_resolution)
    d = material.ndf_cells(2, 3)
    assert d.shape == solid_angles.shape and directions.shape == (d.size, 3)
    # The projected-area normalisation (docs/ndfs.md), to the table's midpoint quadrature.
    assert np.sum(d * directions[:, 2] * solid_angles) == pytest.approx(1.0, rel=0.02)
    # At the cell centres the interpolated NDF is the table.
    np.testing.assert_allclose(material.ndf_at(2, 3, directions), d, rtol=1e-6)
    grid = svbtdf.ndf_grid(material, 2, 3, size=16)
    assert grid.shape == (16, 16) and np.isnan(grid[0, 0]) and grid[8, 8] > 0


def test_sample_and_pdf_agree_with_each_other_and_with_eval(material):
    n = 200_000
    rng = np.random.default_rng(5)
    wo = np.array([0.3, -0.2, 0.9])
    wi, pdf, weight, valid = material.sample([3, 1], wo, rng.random((n, 3)))
    assert wi.shape == (n, 3) and pdf.shape == (n,) and weight.shape == (n, 3) and valid.dtype == np.bool_
    assert valid.mean() > 0.5 and (wi[valid, 2] < 0).all()
    np.testing.assert_allclose(material.pdf([3, 1], wi[valid][:2000], wo), pdf[valid][:2000], rtol=1e-6)
    f = material.bsdf_eval([3, 1], wi[valid][:2000], wo)
    np.testing.assert_allclose(weight[valid][:2000], f * np.abs(wi[valid][:2000, 2:3]) / pdf[valid][:2000, None],
                               rtol=1e-6)

    # The histogram of the draws over 4 x 4 bins of equal solid angle (cos theta, phi) against the
    # pdf integrated over each bin (midpoint rule, 30 x 30 points a bin): chi-square.
    bins = 4
    z_edges = np.linspace(0, 1, bins + 1)
    cos_theta, phi = -wi[valid, 2], np.mod(np.arctan2(wi[valid, 1], wi[valid, 0]), 2 * np.pi)
    counts, _, _ = np.histogram2d(cos_theta, phi, bins=[z_edges, np.linspace(0, 2 * np.pi, bins + 1)])
    m = 30
    zs = (np.arange(bins * m) + 0.5) / (bins * m)
    ps = (np.arange(bins * m) + 0.5) / (bins * m) * 2 * np.pi
    Z, P = np.meshgrid(zs, ps, indexing="ij")
    s = np.sqrt(1 - Z ** 2)
    points = np.stack([s * np.cos(P), s * np.sin(P), -Z], axis=-1).reshape(-1, 3)
    density = material.pdf([3, 1], points, wo).reshape(bins * m, bins * m)
    cell = (1.0 / (bins * m)) * (2 * np.pi / (bins * m))
    expected = density.reshape(bins, m, bins, m).sum(axis=(1, 3)) * cell * n
    # The pdf's mass is the fraction of valid draws (the rest carry no light).
    assert expected.sum() / n == pytest.approx(valid.mean(), rel=0.02)
    keep = expected > 20
    chi2 = np.sum((counts[keep] - expected[keep]) ** 2 / expected[keep])
    assert chi2 < 3 * keep.sum() + 30, (counts, expected)
