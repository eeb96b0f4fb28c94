"""One error tree: every exception class the package defines derives from EosError."""

from __future__ import annotations

import ast
import importlib
import inspect
import pkgutil
from pathlib import Path

import pytest

import eos_svc
from eos_svc import Board, Controller
from eos_svc.agent import ActionResult, Agent, Outcome
from eos_svc.errors import ContractError, EosError, FieldError, NotFoundError, ValidationError

PACKAGE_DIR = Path(eos_svc.__file__).parent


def _all_modules() -> list[str]:
    names = ["eos_svc"]
    for info in pkgutil.walk_packages([str(PACKAGE_DIR)], prefix="eos_svc."):
        if not info.name.endswith("__main__"):  # running it would start the command line
            names.append(info.name)
    return names


def _exception_classes() -> list[type[BaseException]]:
    found: dict[str, type[BaseException]] = {}
    for name in _all_modules():
        module = importlib.import_module(name)
        for _, obj in inspect.getmembers(module, inspect.isclass):
            if issubclass(obj, BaseException) and obj.__module__.startswith("eos_svc"):
                found[f"{obj.__module__}.{obj.__qualname__}"] = obj
    return [found[k] for k in sorted(found)]


def _class_names_in_source() -> set[str]:
    """Every class in the package's source whose bases name an exception (a cross-check that
    the import walk saw them all, nested or private ones included)."""
    names = set()
    for path in PACKAGE_DIR.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ClassDef) and any(
                (isinstance(b, ast.Name) and (b.id.endswith(("Error", "Exception")) or b.id == "EosError"))
                or (isinstance(b, ast.Attribute) and b.attr.endswith(("Error", "Exception")))
                for b in node.bases
            ):
                names.add(node.name)
    return names


def test_every_exception_class_derives_from_eos_error():
    classes = _exception_classes()
    seen = {c.__name__ for c in classes}
    assert _class_names_in_source() <= seen, "an exception class was not reached by the import walk"
    assert len(classes) >= 15
    outside = [f"{c.__module__}.{c.__qualname__}" for c in classes if not issubclass(c, EosError)]
    assert outside == []


def test_every_exception_class_keeps_a_standard_base_and_field_reason():
    for cls in _exception_classes():
        if cls in (EosError, FieldError):  # the two abstract roots
            continue
        roots = (Exception, BaseException, object)
        standard = [b for b in cls.__mro__ if b.__module__ == "builtins" and b not in roots]
        if issubclass(cls, FieldError):
            assert standard, f"{cls.__qualname__} has no standard base (ValueError, TypeError, KeyError...)"
            params = list(inspect.signature(cls.__init__).parameters)
            assert "field" in params and "reason" in params, cls


@pytest.mark.parametrize(
    "make, base, field",
    [
        (lambda: Board().set("", 1), TypeError, "key"),
        (lambda: _Nop("", ["s"], 0.5), ValueError, "agents.name"),
        (lambda: _Nop("a", [], 0.5), ValueError, "agents.a.stages"),
        (lambda: _Nop("a", ["s"], 1.5), ValueError, "agents.a.default"),
    ],
)
def test_core_errors_name_the_field(make, base, field):
    with pytest.raises(FieldError) as info:
        make()
    assert isinstance(info.value, base) and isinstance(info.value, EosError)
    assert info.value.field == field
    assert info.value.to_dict() == {"field": field, "reason": info.value.reason}


def test_kinematics_errors_are_validation_errors():
    from eos_svc.kinematics import load_hand
    from eos_svc.kinematics.hand import UnknownNameError, UrdfLoadError

    with pytest.raises(UrdfLoadError) as info:
        load_hand("/nonexistent/hand.urdf")
    assert isinstance(info.value, ValidationError) and info.value.field == "urdf_path"
    hand = load_hand()
    with pytest.raises(NotFoundError) as unknown:
        hand.tip_radius("finger9")
    assert isinstance(unknown.value, UnknownNameError) and isinstance(unknown.value, KeyError)
    assert str(unknown.value).startswith("finger: unknown finger 'finger9'")


def test_a_broken_agent_contract_is_reported_with_its_class():
    class Broken(Agent):
        def act(self, board, ctx):
            return "done"

    result = Controller([Broken("b", ["s"], 0.5)], ["s"]).run()
    assert result.status.value == "error"
    assert "ContractError" in result.reason and "agents.b.act" in result.reason
    assert issubclass(ContractError, TypeError)


class _Nop(Agent):
    def act(self, board, ctx):
        return ActionResult(Outcome.FINISHED, succeeded=True)
