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


def test_grid_values_are_the_exact_decimals_rounded_also_for_many_points():
    """Each value is the double nearest to START + i (STOP - START)/(COUNT - 1), the exact
    decimal (Fraction arithmetic, one value at a time, is the reference), on the
    vectorised path and on the one for many-digit decimals."""
    from fractions import Fraction

    for text in ("v=-3.7:12.123:997", "x=0.1:0.7:20003", "y=1e-300:1e-299:5",
                 "z=1.23456789012345678:2:7", "w=-1e20:3e20:11"):
        name, ends = text.split("=")
        lo, hi, count = ends.split(":")
        lo, hi, count = Fraction(lo), Fraction(hi), int(count)
        expected = [float(lo + i * (hi - lo) / (count - 1)) for i in range(count)]
        assert list(grid([parse_over(text)]).coordinates[name]) == expected, text


def test_a_grid_too_large_is_refused_from_its_counts_before_any_value_is_made(monkeypatch):
    import nhham.study.points as points

    def no_values(*args):
        raise AssertionError("values made for a design that is refused")

    monkeypatch.setattr(points, "_decimal_grid", no_values)
    axes = [parse_over("a=0:1:10000000"), parse_over("b=0:1:10000000"),
            parse_over("c=0:1:10000000")]
    with pytest.raises(InputError, match=r"10000000 x 10000000 x 10000000 = "
                                         r"1000000000000000000000 points; at most 10000000"):
        grid(axes)


@pytest.mark.parametrize("text", ["k=1e-400:1:3", "k=0:1e-400:3", "k=1e-400,1", "k=-1e-999:1"])
def test_a_number_beyond_double_precision_is_refused_as_in_a_scene(text):
    with pytest.raises(InputError, match="'-?1e-[0-9]+' is outside the range of double "
                                         "precision") as info:
        parse_over(text)
    assert info.value.key == "--over"
    assert parse_over("k=1e-310:1:3").values[0] == 1e-310      # subnormal: a double


def test_a_negative_seed_is_refused_naming_it():
    with pytest.raises(InputError, match="--seed: a non-negative integer, got -1") as info:
        samples([parse_over("x=0:1")], 4, seed=-1)
    assert info.value.key == "--seed"


def test_a_line_longer_than_a_chunk_is_cut_when_filled_first():
    regions = chunk_slices((1000, 3), 256, first=0)
    assert len(regions) == 12 and all(r[1] == slice(0, 1) for r in regions[::3])
    assert {r[0].stop - r[0].start for r in regions} == {250}
    # a line that fits is kept whole, as many lines as fit
    assert chunk_slices((10, 30), 25, first=0)[0] == (slice(0, 10), slice(0, 2))
