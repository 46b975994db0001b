"""Designs: grids at the decimals the user wrote, samples that stratify, chunks that tile."""

import numpy as np
import pytest

from nhham.errors import InputError
from nhham.study.points import chunk_slices, grid, parse_over, parse_perturbation, samples


def test_grid_values_are_the_decimals_written():
    axis = parse_over("m=0:1:11")
    assert axis.values == (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)
    assert repr(axis.values[3]) == "0.3"          # linspace gives 0.30000000000000004
    assert parse_over("c=0:0.2:101").values[40] == 0.08
    assert parse_over(" k = 1e-3 : 2e-3 : 3 ").values == (0.001, 0.0015, 0.002)
    assert parse_over("b=1,2,5").values == (1.0, 2.0, 5.0)
    assert parse_over("v=0:10").count is None and parse_over("v=0:10").bounds == (0.0, 10.0)


@pytest.mark.parametrize("text, fragment", [
    ("v", "expected NAME=START:STOP:COUNT"), ("v=1:0:3", "START < STOP"),
    ("v=0:1:0", "COUNT must be between"), ("v=0:x:3", "must be numbers"),
    ("v=1,1", "distinct"), ("v=0:inf:3", "finite")])
def test_bad_axes_name_the_option(text, fragment):
    with pytest.raises(InputError, match=fragment) as info:
        parse_over(text)
    assert info.value.key == "--over"


def test_grid_regions_and_values():
    design = grid([parse_over("a=0:1:3"), parse_over("b=10,20")])
    assert design.shape == (3, 2) and design.dims == ("a", "b") and design.size == 6
    vals = design.values((slice(1, 3), slice(0, 2)))
    assert vals["a"].tolist() == [[0.5, 0.5], [1.0, 1.0]]
    assert vals["b"].tolist() == [[10.0, 20.0], [10.0, 20.0]]
    with pytest.raises(InputError, match="given twice"):
        grid([parse_over("a=0:1:3"), parse_over("a=0:1:2")])
    with pytest.raises(InputError, match="needs a COUNT"):
        grid([parse_over("a=0:1")])


def test_latin_hypercube_puts_one_point_in_each_stratum():
    K = 64
    design = samples([parse_over("x=-1:3"), parse_over("y=0:0.5")], K, sampler="lhs", seed=4)
    for name, (lo, hi) in (("x", (-1, 3)), ("y", (0, 0.5))):
        v = design.coordinates[name]
        assert v.min() >= lo and v.max() <= hi
        assert sorted(np.floor(K * (v - lo) / (hi - lo)).astype(int)) == list(range(K))
    again = samples([parse_over("x=-1:3"), parse_over("y=0:0.5")], K, sampler="lhs", seed=4)
    assert np.array_equal(again.coordinates["x"], design.coordinates["x"])


def test_sobol_and_uniform_stay_in_range_and_perturbations_have_their_spread():
    for sampler in ("sobol", "uniform"):
        d = samples([parse_over("x=2:3")], 128, sampler=sampler, seed=1)
        assert 2 <= d.coordinates["x"].min() and d.coordinates["x"].max() <= 3
    d = samples([], 20000, seed=2, perturbations=[parse_perturbation("phi=0.01"),
                                                   ("x", 2.0)])
    assert d.perturbed == ("phi", "x") and d.perturbations.shape == (20000, 2)
    assert np.allclose(d.perturbations.std(axis=0), [0.01, 2.0], rtol=0.03)
    assert np.allclose(d.perturbations.mean(axis=0), 0, atol=[3e-4, 0.06])
    with pytest.raises(InputError, match="NAME=SIGMA"):
        parse_perturbation("phi=-1")


@pytest.mark.parametrize("shape, points, whole", [((201, 101), 4096, 0), ((7, 5, 3), 10, None),
                                                  ((1000,), 256, None), ((5, 9), 1, 1)])
def test_chunks_cover_every_point_once(shape, points, whole):
    count = np.zeros(shape, dtype=int)
    regions = chunk_slices(shape, points, whole)
    for region in regions:
        count[region] += 1
        if whole is not None:
            assert region[whole] == slice(0, shape[whole])
    assert (count == 1).all()
    line = shape[whole] if whole is not None else 1
    for r in regions:   # about `points` each, never less than a whole line
        assert np.prod([len(range(*s.indices(n))) for s, n in zip(r, shape)]) <= max(points,
                                                                                   line)


def test_chunks_are_even():
    # 101 lines of 201 points in chunks of at most 4096: 6 chunks of 17 or 16 lines (not
    # five of 20 and a last of one, which leaves a worker idle at the end)
    regions = chunk_slices((201, 101), 4096, 0)
    assert sorted(r[1].stop - r[1].start for r in regions) == [16, 17, 17, 17, 17, 17]
    assert sorted({r[0].stop - r[0].start for r in chunk_slices((1000,), 256)}) == [250]
