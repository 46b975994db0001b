"""The generated sources (nhham.numerics.codegen.emit): sums of angles expanded only when
that saves calls, and sources kept by the content of the system, not by the object."""

from __future__ import annotations

import sympy as sp

import nhham
from nhham.numerics.codegen import c_compiler, numeric_model

from test_exact_solutions import chaplygin_sleigh, rolling_disk

HAVE_CC = c_compiler() is not None


def test_angle_sums_expanded_only_when_no_new_calls():
    """sin/cos(theta_i - theta_j) become products of the sin/cos of the angles
    when those are computed anyway (the snake: one sincos per angle instead of
    one per pair); otherwise (the snakeboard's theta +- phi) they are kept."""
    from nhham.numerics.codegen.emit import expand_angle_sums

    a, b, c = sp.symbols("a b c", real=True)
    out = expand_angle_sums([sp.sin(a - b) + sp.cos(a) * sp.sin(b)], [a, b])
    assert out[0].atoms(sp.sin, sp.cos) <= {sp.sin(a), sp.cos(a), sp.sin(b), sp.cos(b)}
    assert sp.simplify(out[0] - sp.sin(a - b) - sp.cos(a) * sp.sin(b)) == 0
    kept = [sp.sin(a + b) * sp.cos(b)]  # sin(a) / cos(a) not computed: no gain
    assert expand_angle_sums(kept, [a, b]) == kept
    three = expand_angle_sums([sp.cos(a + b - c), sp.sin(a), sp.cos(b), sp.sin(c)], [a, b, c])
    assert sp.simplify(three[0] - sp.cos(a + b - c)) == 0
    if HAVE_CC:
        snake = numeric_model(nhham.models.snake(5), backend="c")
        saddle = snake.c_source.split("static void saddle(")[-1].split("\n}\n")[0]
        calls = saddle.count("sin(") + saddle.count("cos(")
        assert calls == 2 * 5  # one sin and one cos per link angle


def test_generated_sources_are_kept_by_content_not_by_identity():
    """Equal systems share their generated sources; a system is not kept alive by them;
    a different system, or another path, gets its own."""
    import gc
    import weakref

    from nhham.numerics.codegen.emit import generate_sources, system_fingerprint

    a, b = chaplygin_sleigh(), chaplygin_sleigh()
    assert a is not b and system_fingerprint(a) == system_fingerprint(b)
    # the same texts (the objects: generated once), each with its system's layout
    assert generate_sources(a)["python"] is generate_sources(b)["python"]
    assert system_fingerprint(a) != system_fingerprint(a, "closed_form")
    assert system_fingerprint(rolling_disk()) != system_fingerprint(a)
    ref = weakref.ref(a)
    numeric_model(a, backend="numpy")
    del a
    gc.collect()
    assert ref() is None


def test_the_key_of_an_expression_is_its_structure_not_how_it_was_built():
    """Equal Lagrangians give one fingerprint whether a subexpression is one shared object
    or two equal copies (a pickle wrote them differently: the bicycle's sources were
    generated again for every load after its geometry, 8 times in the suite); a symbol's
    assumptions and an exact 1 against a float 1.0 still tell expressions apart."""
    import pickle

    from nhham.numerics.codegen.emit import expression_digest, system_fingerprint

    x, xd, m = sp.symbols("x x_dot m", real=True)
    shared = m * sp.sin(x)
    one = sp.cos(shared) * xd ** 2 + sp.sin(shared)  # one object, twice in the tree
    sp.core.cache.clear_cache()  # the next product is a new object, equal to the first
    copy = sp.Mul(m, sp.sin(x))
    two = sp.cos(shared) * xd ** 2 + sp.sin(copy)
    assert one == two and copy is not shared
    assert pickle.dumps(one, protocol=4) != pickle.dumps(two, protocol=4)  # the old key
    assert expression_digest(one) == expression_digest(two)
    systems = [nhham.System(["x"], L, parameters={"m": 1.0}, name="same") for L in (one, two)]
    assert system_fingerprint(systems[0]) == system_fingerprint(systems[1])
    assert expression_digest(sp.Symbol("x") * xd) != expression_digest(x * xd)
    assert expression_digest(sp.Float(1.0) * x) != expression_digest(sp.Integer(1) * x)


def test_the_code_digest_covers_the_generator_and_what_it_imports_only():
    """generator_files (import lines read by a regular expression) against the imports
    ast finds, function-level ones included: closed under import, and an edit of a
    command or a renderer leaves the models' sources valid."""
    import ast
    from pathlib import Path

    from nhham.numerics.codegen.emit import generator_files

    package = Path(nhham.__file__).resolve().parent
    files = set(generator_files())
    names = {str(f.relative_to(package)) for f in files}
    assert {"numerics/codegen/emit.py", "numerics/codegen/python_text.py",
            "lagrangian/geometry.py", "system/expressions.py", "numerics/c/rhs.c",
            "numerics/c/nhham.h"} <= names
    assert not names & {"cli/main.py", "render/results.py", "numerics/integrate.py",
                        "journeys/derivation.py", "problems/catalog.py"}
    for f in (f for f in files if f.suffix == ".py"):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("nhham"):
                targets = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names if a.name.startswith("nhham")]
            else:
                continue
            for target in targets:
                path = package.joinpath(*target.split(".")[1:])
                module = path.with_suffix(".py")
                if module.is_file():
                    assert module in files, f"{f.name} imports {target}: not in the digest"


def _bead_on_a_parabola(extra):
    """m (x'^2 + y'^2)/2 - k x^2/2 with y' = a x x' and the force b sin(t) on x; ``extra``:
    parameters that enter nothing."""
    values = {"a": 0.5, "b": 0.3, **extra, "k": 2.0, "m": 1.5}
    return nhham.System(["x", "y"], "m*(x_dot**2 + y_dot**2)/2 - k*x**2/2",
                        constraints=["y_dot - a*x*x_dot"], parameters=values,
                        forces={"x": "b*sin(t)"}, name="bead")


def test_a_parameter_that_enters_nothing_leaves_the_compiled_library_alone():
    """The kernels read only the parameters the expressions use: one more parameter,
    declared between the others, generates and compiles nothing new (the sources and the
    library shared), and the numbers are the closed form's, t included (its slot moves in
    the kernels' vector), on numpy and C, in the compiled loop and the complex step."""
    import math

    import numpy as np

    from nhham.numerics.codegen.emit import kernel_parameters, source_key

    plain, more = _bead_on_a_parabola({}), _bead_on_a_parabola({"c": 7.0, "d": -1.0})
    assert [p.name for p in more.parameters] == ["a", "b", "c", "d", "k", "m", "t"]
    assert kernel_parameters(more) == (0, 1, 4, 5, 6)
    models = [numeric_model(s, backend="numpy") for s in (plain, more)]
    assert source_key(plain) == source_key(more)   # the sources are shared too
    assert models[0].c_source == models[1].c_source
    assert models[0].c_complex_source == models[1].c_complex_source
    assert models[0].python_source == models[1].python_source
    assert models[1].parameter_names == ("a", "b", "c", "d", "k", "m", "t")
    assert models[1].time_slot == 6 and models[0].time_slot == 4
    if HAVE_CC:
        models += [numeric_model(s, backend="c") for s in (plain, more)]
        assert models[2].compiled.path == models[3].compiled.path
    # x''(m + m a^2 x^2) = -k x + b sin t - m a^2 x x'^2, y'' = a x'^2 + a x x''
    x, xd, t = 0.4, -0.8, 0.7
    a, b, k, m = 0.5, 0.3, 2.0, 1.5
    xdd = (-k * x + b * math.sin(t) - m * a * a * x * xd * xd) / (m + m * a * a * x * x)
    want = [xd, a * x * xd, xdd, a * xd * xd + a * x * xdd]
    for model in models:
        y = model.state({"x": x, "y": 0.2, "x_dot": xd, "y_dot": a * x * xd})
        np.testing.assert_allclose(model.rhs(t, y), want, rtol=1e-13, atol=1e-15)
    if HAVE_CC:   # the compiled loop writes t into the C vector's own slot
        from nhham.numerics.integrate import simulate

        ends = [simulate(model, (0.0, 2.0), y, rtol=1e-10,
                         atol=1e-12).y[:, -1] for model in models[2:]]
        np.testing.assert_array_equal(ends[0], ends[1])
        # the complex-step kernels read the same compact vector
        from nhham.numerics.chart import ComplexField

        Q, V = np.array([[x, 0.2]]), np.array([[xd, a * x * xd]])
        compiled, numpy = ComplexField(models[3], build=True), ComplexField(models[1])
        assert compiled.backend == "c" and numpy.backend == "numpy"
        for got, ref in zip(compiled.pieces(Q, V), numpy.pieces(Q, V)):
            np.testing.assert_allclose(got, ref, rtol=1e-14, atol=1e-15)
