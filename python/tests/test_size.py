"""The size field from Python: the size flags as dicts and lists,
and ``size_fn``, a function of numpy arrays called back in batches while
meshing. The drawing is the size-field fixture of the Rust tests: a 100 x 100
plate with a ``steel`` disk and a ``rubber`` ellipse (y is up: the drawing's
y = 50 is -50)."""

from __future__ import annotations

import threading

import numpy as np
import pytest

import triwild
from conftest import REPO

PLATE = REPO / "tests" / "fixtures" / "plate.svg"
BASE = dict(cut_outside=True, edge_length_abs=5)


def assert_same_mesh(a: triwild.Mesh, b: triwild.Mesh) -> None:
    np.testing.assert_array_equal(a.points, b.points)  # exactly
    np.testing.assert_array_equal(a.triangles, b.triangles)
    np.testing.assert_array_equal(a.region, b.region)
    assert a.region_names == b.region_names


def test_size_fn_gives_the_mesh_of_the_same_formula():
    calls = []

    def f(x, y):
        calls.append((type(x), x.dtype, x.shape, y.shape))
        return 0.5 + 0.05 * x

    by_fn = triwild.mesh(PLATE, size_fn=f, **BASE)
    by_expr = triwild.mesh(PLATE, size_expr="0.5 + 0.05*x", **BASE)
    assert_same_mesh(by_fn, by_expr)
    assert len(by_fn.triangles) > len(triwild.mesh(PLATE, **BASE).triangles)
    assert "size-fn" in by_fn.stats["sizing"]["fields"]
    # numpy float64 arrays of one batch each, x and y alike
    assert calls and all(t is np.ndarray and d == np.float64 and s == sy for t, d, s, sy in calls)


def test_size_fn_is_called_in_batches():
    sizes = []

    def f(x, y):
        sizes.append(len(x))
        return np.full(len(x), 2.0)

    triwild.mesh(PLATE, size_fn=f, order=1, **BASE)
    assert sizes and min(sizes) >= 1
    assert max(sizes) > 1, sizes
    # far fewer calls than points asked for: never point by point
    assert len(sizes) < sum(sizes) / 10, sizes


def test_size_fn_gives_the_same_mesh_on_one_and_two_threads():
    f = lambda x, y: 0.5 + 0.05 * x  # noqa: E731
    one = triwild.mesh(PLATE, size_fn=f, threads=1, **BASE)
    two = triwild.mesh(PLATE, size_fn=f, threads=2, **BASE)
    assert_same_mesh(one, two)


def test_size_fn_runs_while_other_python_threads_run():
    # meshing releases the GIL and each batch takes it again: a thread that
    # counts meanwhile keeps counting, and two meshes at once both finish
    done = threading.Event()
    ticks = [0]

    def count():
        while not done.is_set():
            ticks[0] += 1

    results = [None, None]

    def work(i):
        results[i] = triwild.mesh(PLATE, size_fn=lambda x, y: 1.0 + 0.0 * x, order=1, **BASE)

    counter = threading.Thread(target=count)
    counter.start()
    workers = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in workers:
        t.start()
    for t in workers:
        t.join()
    done.set()
    counter.join()
    assert ticks[0] > 0
    assert_same_mesh(results[0], results[1])


def test_the_dict_and_list_forms_equal_the_strings():
    as_strings = triwild.mesh(
        PLATE,
        size=["steel=1", "rubber=2"],
        size_near="steel=0.5:10",
        size_box="45,-65,95,-35=1",
        order=1,
        **BASE,
    )
    as_python = triwild.mesh(
        PLATE,
        size={"steel": 1, "rubber": 2.0},
        size_near={"steel": (0.5, 10)},
        size_box=[(45, -65, 95, -35, 1)],
        order=1,
        **BASE,
    )
    assert_same_mesh(as_strings, as_python)
    applied = as_python.stats["sizing"]["fields"]
    assert {"size", "size-box"} <= set(applied), applied


@pytest.mark.parametrize(
    "kwargs,flags",
    [
        ({"size": "steel=1"}, ["--size=steel=1"]),
        ({"size": {"steel": 1, "rubber": 0.5}}, ["--size=steel=1", "--size=rubber=0.5"]),
        ({"size": ["steel=1", "rubber=2"]}, ["--size=steel=1", "--size=rubber=2"]),
        ({"size_near": {"steel": 0.5}}, ["--size-near=steel=0.5"]),
        ({"size_near": {"steel": (0.5, 10)}}, ["--size-near=steel=0.5:10"]),
        ({"size_near": "steel=0.5:10"}, ["--size-near=steel=0.5:10"]),
        ({"size_box": (45, -65, 95, -35, 1)}, ["--size-box=45,-65,95,-35=1"]),
        (
            {"size_box": [(45, -65, 95, -35, 1), (0, 0, 1, 1, 0.25)]},
            ["--size-box=45,-65,95,-35=1", "--size-box=0,0,1,1=0.25"],
        ),
        ({"size_box": ["45,-65,95,-35=1"]}, ["--size-box=45,-65,95,-35=1"]),
    ],
)
def test_size_forms_become_the_command_lines_flags(kwargs, flags):
    assert triwild._flags(kwargs) == flags


@pytest.mark.parametrize(
    "kwargs",
    [{"size": [("steel", 1)]}, {"size_near": {"steel": (1, 2, 3)}}, {"size_box": [(1, 2, 3)]}, {"size": {1: 2}}],
)
def test_bad_size_forms_are_type_errors(kwargs):
    with pytest.raises(TypeError):
        triwild._flags(kwargs)


def test_a_size_fn_that_is_not_callable_is_a_type_error():
    with pytest.raises(TypeError, match="size_fn"):
        triwild.mesh(PLATE, size_fn=0.5, **BASE)


def _raising(x, y):
    raise ZeroDivisionError("no size here")


def _nan_right_half(x, y):
    return np.where(x > 50, np.nan, 1.0)


def _one_short(x, y):
    return np.ones(len(x) - 1)


def _non_positive(x, y):
    return 20.0 - x


def _two_dimensional(x, y):
    return np.ones((len(x), 2))


@pytest.mark.parametrize(
    "f,cause,chained",
    [
        (_raising, "ZeroDivisionError: no size here", ZeroDivisionError),
        (_nan_right_half, "gave NaN at (", None),
        (_one_short, "values for a batch of", None),
        (_non_positive, "not a positive finite size", None),
        (_two_dimensional, "ValueError: size_fn returned an array of shape", ValueError),
    ],
    ids=["raises", "nan", "wrong-length", "non-positive", "2-d"],
)
def test_a_bad_size_fn_is_bad_input_naming_the_point(f, cause, chained):
    with pytest.raises(triwild.Error) as info:
        triwild.mesh(PLATE, size_fn=f, **BASE)
    err = info.value
    assert isinstance(err, triwild.BadInput), type(err)
    msg = str(err)
    assert "\n" not in msg
    assert "the size function" in msg and cause in msg, msg
    assert " at (" in msg, msg  # the point (a batch's: its first)
    if chained is None:
        assert err.__cause__ is None
    else:
        assert isinstance(err.__cause__, chained), repr(err.__cause__)
