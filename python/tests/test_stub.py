"""The stub, strata_rt/_native.pyi, says what the compiled module has.

Every public function, class, method, property and value of
``strata_rt._native`` is in the stub, and each of the stub's is in the
module, with the parameters ``inspect`` reads from the compiled signatures:
the same names in the same order, of the same kinds, with the same
defaults (an ``@overload`` may write ``...`` for a default). The stub is
read with ``ast``, never imported. tests/suite/python_settings.rs holds
``render``'s keywords to strata's render settings (``RenderOverrides``).
"""

import ast
import inspect
import types

import pytest

import helpers
from strata_rt import _native

STUB = helpers.REPO / "python" / "strata_rt" / "_native.pyi"

#: What every module has, whoever wrote it: not the stub's business.
MODULE_DUNDERS = {"__name__", "__doc__", "__file__", "__loader__", "__package__", "__spec__", "__all__"}


def public(name: str) -> bool:
    return not name.startswith("_") or name == "__version__"


def stub_module():
    """The stub's top level: {name: [FunctionDef, ...] | ClassDef | AnnAssign}."""
    out = {}
    for node in ast.parse(STUB.read_text()).body:
        if isinstance(node, ast.FunctionDef):
            out.setdefault(node.name, []).append(node)
        elif isinstance(node, ast.ClassDef):
            out[node.name] = node
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            out[node.target.id] = node
    return {name: node for name, node in out.items() if public(name)}


NO_DEFAULT = object()


def stub_params(fn: ast.FunctionDef):
    """[(name, kind, default source or NO_DEFAULT)] of a stub's def."""
    a = fn.args
    P = inspect.Parameter
    positional = [(x, P.POSITIONAL_ONLY) for x in a.posonlyargs] + [
        (x, P.POSITIONAL_OR_KEYWORD) for x in a.args
    ]
    defaults = [NO_DEFAULT] * (len(positional) - len(a.defaults)) + [ast.unparse(d) for d in a.defaults]
    out = [(x.arg, kind, d) for (x, kind), d in zip(positional, defaults)]
    if a.vararg:
        out.append((a.vararg.arg, P.VAR_POSITIONAL, NO_DEFAULT))
    for x, d in zip(a.kwonlyargs, a.kw_defaults):
        out.append((x.arg, P.KEYWORD_ONLY, NO_DEFAULT if d is None else ast.unparse(d)))
    if a.kwarg:
        out.append((a.kwarg.arg, P.VAR_KEYWORD, NO_DEFAULT))
    return out


def runtime_params(obj):
    """[(name, kind, default or NO_DEFAULT)] of a compiled callable."""
    try:
        signature = inspect.signature(obj)
    except ValueError as err:
        pytest.fail(f"{obj!r} has no signature inspect can read: {err}")
    return [
        (p.name, p.kind, NO_DEFAULT if p.default is inspect.Parameter.empty else p.default)
        for p in signature.parameters.values()
    ]


def same_params(where: str, stub, runtime, dunder: bool = False):
    """Fails unless the stub's parameters are the module's."""
    # Python passes a protocol method's arguments by position, whatever
    # the stub calls their kind.
    loose = {inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD}
    names = ([n for n, _, _ in stub], [n for n, _, _ in runtime])
    assert names[0] == names[1] or dunder and len(names[0]) == len(names[1]), (
        f"{where}: the stub has {names[0]}, the module {names[1]}"
    )
    for (name, kind, default), (_, r_kind, r_default) in zip(stub, runtime):
        same_kind = kind == r_kind or dunder and {kind, r_kind} <= loose
        assert same_kind, f"{where}: {name} is {kind.description} in the stub, {r_kind.description} in the module"
        if default is NO_DEFAULT or r_default is NO_DEFAULT:
            assert (default is NO_DEFAULT) == (r_default is NO_DEFAULT), (
                f"{where}: {name} has a default in one of the stub and the module only"
            )
        elif default != "...":
            assert ast.literal_eval(default) == r_default, (
                f"{where}: {name} defaults to {default} in the stub, {r_default!r} in the module"
            )


def without_self(params):
    return params[1:] if params and params[0][0] == "self" else params


def decorators(fn: ast.FunctionDef):
    return {ast.unparse(d) for d in fn.decorator_list}


def test_the_stub_and_the_module_name_the_same_things():
    in_module = {n for n in vars(_native) if public(n) and n not in MODULE_DUNDERS}
    assert set(stub_module()) == in_module


@pytest.mark.parametrize("name", sorted(n for n, v in stub_module().items() if isinstance(v, list)))
def test_each_function_takes_what_its_stub_says(name):
    runtime = runtime_params(getattr(_native, name))
    for overload in stub_module()[name]:
        where = f"{name} (stub line {overload.lineno})"
        same_params(where, stub_params(overload), runtime)


@pytest.mark.parametrize("name", sorted(n for n, v in stub_module().items() if isinstance(v, ast.ClassDef)))
def test_each_class_has_what_its_stub_says(name):
    node = stub_module()[name]
    cls = getattr(_native, name)
    assert isinstance(cls, type), f"{name} is a class in the stub, a {type(cls).__name__} in the module"
    bases = [ast.unparse(b) for b in node.bases]
    assert bases == [b.__name__ for b in cls.__bases__ if b is not object]
    members = {}
    for item in node.body:
        if isinstance(item, ast.FunctionDef):
            members.setdefault(item.name, []).append(item)
    in_module = {n for n in vars(cls) if not n.startswith("_")}
    assert {n for n in members if not n.startswith("_")} == in_module, name
    for member, defs in members.items():
        where = f"{name}.{member}"
        if member == "__init__":
            runtime = runtime_params(cls)
            for d in defs:
                same_params(where, without_self(stub_params(d)), runtime)
            continue
        assert hasattr(cls, member), f"{where} is in the stub, not in the module"
        static = inspect.getattr_static(cls, member)
        for d in defs:
            if "property" in decorators(d):
                assert isinstance(static, (property, types.GetSetDescriptorType, types.MemberDescriptorType)), (
                    f"{where} is a property in the stub, a {type(static).__name__} in the module"
                )
                continue
            runtime = runtime_params(getattr(cls, member))
            params = stub_params(d)
            if "staticmethod" not in decorators(d):
                params, runtime = without_self(params), runtime[1:]
            same_params(where, params, runtime, dunder=member.startswith("__"))


def test_values_have_their_stub_types():
    for name, node in stub_module().items():
        if isinstance(node, ast.AnnAssign):
            kind = ast.unparse(node.annotation)
            assert type(getattr(_native, name)).__name__ == kind, f"{name}: {kind} in the stub"


def test_the_checks_can_fail():
    """A stub that drifted from the module fails the comparison."""
    P = inspect.Parameter
    runtime = [("a", P.POSITIONAL_OR_KEYWORD, NO_DEFAULT), ("b", P.KEYWORD_ONLY, None)]
    same_params("ok", [("a", P.POSITIONAL_OR_KEYWORD, NO_DEFAULT), ("b", P.KEYWORD_ONLY, "None")], runtime)
    for drifted in (
        [("a", P.POSITIONAL_OR_KEYWORD, NO_DEFAULT)],
        [("a", P.POSITIONAL_OR_KEYWORD, NO_DEFAULT), ("c", P.KEYWORD_ONLY, "None")],
        [("a", P.POSITIONAL_OR_KEYWORD, NO_DEFAULT), ("b", P.POSITIONAL_OR_KEYWORD, "None")],
        [("a", P.POSITIONAL_OR_KEYWORD, NO_DEFAULT), ("b", P.KEYWORD_ONLY, "0")],
        [("a", P.POSITIONAL_OR_KEYWORD, NO_DEFAULT), ("b", P.KEYWORD_ONLY, NO_DEFAULT)],
    ):
        with pytest.raises(AssertionError):
            same_params("drifted", drifted, runtime)


def stub_method(cls: str, name: str) -> ast.FunctionDef:
    for item in stub_module()[cls].body:
        if isinstance(item, ast.FunctionDef) and item.name == name:
            return item
    pytest.fail(f"the stub has no {cls}.{name}")


def test_the_stub_says_what_pickling_gives():
    """Mesh.__reduce__ gives float64 vertices as given for a mesh of
    float64 arrays that float32 does not hold exactly (float32 corners
    otherwise) and Mesh._placed (not a type) for a placed mesh; the
    results reduce to their own _unpickle. The stub's return types say so."""
    import numpy as np

    mesh = _native.Mesh(np.eye(3) / 3, [[0, 1, 2]])
    call, (vertices, faces) = mesh.__reduce__()
    assert call is _native.Mesh and vertices.dtype == np.float64 and faces.dtype == np.int64
    call, (vertices, faces) = _native.Mesh(np.eye(3), [[0, 1, 2]]).__reduce__()
    assert call is _native.Mesh and vertices.dtype == np.float32
    call, args = mesh.place(np.eye(3, 4)[None]).__reduce__()
    assert call == _native.Mesh._placed and len(args) == 3
    returns = ast.unparse(stub_method("Mesh", "__reduce__").returns)
    assert "Callable" in returns and "np.float64" in returns and "np.float32" in returns, returns
    assert "_placed" in ast.get_docstring(stub_method("Mesh", "__reduce__"))
    o, d = [[0.1, 0.1, 1.0]], [[0.0, 0.0, -1.0]]
    for result in (mesh.intersect(o, d), mesh.all_hits(o, d), mesh.closest_point(o)):
        cls = type(result).__name__
        call, _ = result.__reduce__()
        assert call == getattr(type(result), "_unpickle"), cls
        stub_method(cls, "_unpickle")
        assert "Callable" in ast.unparse(stub_method(cls, "__reduce__").returns), cls


def test_the_stub_s_ray_queries_say_they_take_t_min():
    for query in ("intersect", "occluded", "all_hits", "count_hits"):
        doc = ast.get_docstring(stub_method("Mesh", query))
        assert "(t_min, t_max]" in doc and "(0, t_max]" not in doc, query
