"""The type stubs (urdyn/__init__.pyi) against the extension itself: every public name
of the module and of its classes has a stub, and every stubbed function or method takes
the parameters the extension takes, by name and in order (so that a keyword call written
from the stub or python.md works)."""

import ast
import inspect
from pathlib import Path

import urdyn

STUB = Path(urdyn.__file__).with_name("__init__.pyi")
TREE = ast.parse(STUB.read_text())


def stub_params(fn):
    a = fn.args
    names = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs]
    return names[1:] if names and names[0] in ("self", "cls") else names


def runtime_params(obj):
    try:
        names = list(inspect.signature(obj).parameters)
    except (TypeError, ValueError):
        return None  # not introspectable (a constructor taking *args, **kwargs)
    if names in (["args", "kwargs"],):
        return None
    return names[1:] if names and names[0] in ("self", "cls", "$self") else names


def test_every_stubbed_function_takes_the_extensions_parameters():
    wrong = []
    for node in TREE.body:
        if isinstance(node, ast.FunctionDef):
            rp = runtime_params(getattr(urdyn, node.name))
            if rp is not None and rp != stub_params(node):
                wrong.append((node.name, stub_params(node), rp))
        elif isinstance(node, ast.ClassDef):
            cls = getattr(urdyn, node.name)
            for f in node.body:
                if not isinstance(f, ast.FunctionDef) or f.name.startswith("__"):
                    continue
                obj = inspect.getattr_static(cls, f.name)
                if type(obj).__name__ in ("getset_descriptor", "property"):
                    continue
                rp = runtime_params(getattr(cls, f.name))
                if rp is not None and rp != stub_params(f):
                    wrong.append((f"{node.name}.{f.name}", stub_params(f), rp))
    assert not wrong, wrong


def test_every_public_name_has_a_stub():
    stubbed = {n.name: n for n in TREE.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    missing = [n for n in dir(urdyn) if not n.startswith("_") and callable(getattr(urdyn, n))
               and n not in stubbed]
    for name, node in stubbed.items():
        if not isinstance(node, ast.ClassDef) or issubclass(getattr(urdyn, name), BaseException):
            continue
        members = {f.name for f in node.body if isinstance(f, ast.FunctionDef)}
        members |= {t.target.id for t in node.body if isinstance(t, ast.AnnAssign)}
        missing += [f"{name}.{n}" for n in dir(getattr(urdyn, name))
                    if not n.startswith("_") and n not in members]
    assert not missing, missing


def test_sleeping_takes_model_name_by_keyword():
    model = urdyn.Model.from_urdf(str(Path(__file__).resolve().parents[2] / "assets" / "robots"
                                      / "ur5.urdf"))
    sim = urdyn.Simulation(model)
    assert sim.sleeping(model_name=model.models[0]) is False
