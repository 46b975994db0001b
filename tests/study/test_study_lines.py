"""A linearize grid's lines cut by --chunk: memory bounded by the chunk, and the crossings
of the pieces (also one between two pieces) those of the whole line."""

import numpy as np

import nhham.study.stability as stability
from nhham.study.lines import LINE_VARIABLES, merged
from nhham.study.sweep import sweep

# the differential drive's straight run at wheel rate w: one eigenvalue -mc d r w / J,
# through zero at w = 0, which lies between the 9th and 10th of these 18 points
SCENE = "examples/differential_drive.toml"
LINE = ["w=-4.25:4.25:18"]


def test_a_line_in_pieces_gives_what_the_whole_line_gives(monkeypatch):
    whole = sweep(SCENE, "linearize", LINE, workers=1).dataset
    sizes = []
    evaluate = stability.evaluate

    def recorded(study, ctx, region, until=None):
        sizes.append(region[0].stop - region[0].start)
        return evaluate(study, ctx, region, until=until)

    monkeypatch.setattr(stability, "evaluate", recorded)
    cut = sweep(SCENE, "linearize", LINE, workers=1, chunk_points=9)
    assert cut.chunks == 2 and cut.complete
    # the second piece carries the last point of the first (the bracket across them)
    assert sorted(sizes) == [9, 10]
    for name in whole.data_vars:
        a, b = np.asarray(whole[name].values), np.asarray(cut.dataset[name].values)
        assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), name
    # the closed form: one real crossing, at w = 0, turning stable as w grows
    assert int(cut.dataset["boundary_count"]) == 1
    assert abs(float(cut.dataset["boundary"][0])) < 1e-12
    assert int(cut.dataset["boundary_kind"][0]) == 0
    assert int(cut.dataset["boundary_direction"][0]) == -1


def test_a_one_parameter_grid_is_chunked_like_any_other():
    result = sweep(SCENE, "linearize", ["w=-4:4:101"], workers=1, chunk_points=10)
    assert result.chunks == 11 and result.complete      # ceil(101 / 10) pieces of <= 10


def test_merging_a_piece_twice_counts_it_once():
    """A failure between a piece's line write and its done write merges it again on
    resume: nothing is added twice."""
    empty = {"boundary": np.full((1, 8), np.nan), "boundary_kind": np.full((1, 8), -1),
             "boundary_direction": np.zeros((1, 8), dtype=int),
             "boundary_count": np.full((1,), -1)}
    first = {"boundary": np.array([[2.0] + [np.nan] * 7]),
             "boundary_kind": np.array([[1] + [-1] * 7]),
             "boundary_direction": np.array([[1] + [0] * 7]), "boundary_count": np.array([1])}
    second = {"boundary": np.array([[0.5] + [np.nan] * 7]),
              "boundary_kind": np.array([[0] + [-1] * 7]),
              "boundary_direction": np.array([[-1] + [0] * 7]), "boundary_count": np.array([1])}
    once = merged(merged(empty, first), second)
    twice = merged(merged(once, first), second)
    for name in LINE_VARIABLES:
        assert np.array_equal(once[name], twice[name], equal_nan=True), name
    assert once["boundary"][0, :2].tolist() == [0.5, 2.0]     # sorted along the line
    assert once["boundary_kind"][0, :2].tolist() == [0, 1]
    assert int(once["boundary_count"][0]) == 2


def test_pieces_written_to_a_store_merge_with_what_it_holds(tmp_path):
    """Five pieces of 4 or 2 points written one after the other: the crossing found in
    the third is still there after the fourth and fifth are merged (read back from the
    store, not from what was read when it opened)."""
    whole = sweep(SCENE, "linearize", LINE, workers=1).dataset
    cut = sweep(SCENE, "linearize", LINE, workers=1, chunk_points=4, out=tmp_path / "l.zarr")
    assert cut.chunks == 5 and cut.complete
    for name in whole.data_vars:
        a, b = np.asarray(whole[name].values), np.asarray(cut.dataset[name].values)
        assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), name
