"""make_controller knows no law and no option by name: adding an option touches the spec and its law's file only."""
import ast
from pathlib import Path

import pytest

import flatstep as fs
from flatstep.control import spec as spec_module
from flatstep.control.build import BuildContext
from flatstep.control.spec import ALIASES, LAW_TABLE, LAWS, OPTIONS, ControllerSpec

TUNING = Path(fs.__file__).parent / "control" / "tuning.py"
#: Every name a law or an option goes by in code: the laws, the options, the historical aliases.
NAMES = {*LAWS, *OPTIONS, *ALIASES}
#: ... and in a string, a choice's values too.
STRINGS = NAMES | {v for opt in OPTIONS.values() for v in opt.values}


def names_in(source: str) -> set[str]:
    """The string constants, attribute names and identifiers of a module that are law or option names."""
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            found |= {node.value} & STRINGS
            found |= {w for w in STRINGS if f"{w}+" in node.value or f"'{w}'" in node.value}
        elif isinstance(node, ast.Attribute):
            found |= {node.attr} & NAMES
        elif isinstance(node, ast.Name):
            found |= {node.id} & NAMES
        elif isinstance(node, ast.keyword) and node.arg is not None:
            found |= {node.arg} & NAMES
    return found


def without_docstrings(source: str) -> str:
    """The module's code with its docstrings (module, functions) removed."""
    tree = ast.parse(source)
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr) and isinstance(body[0].value,
                                                                                             ast.Constant):
            node.body = body[1:] or [ast.Pass()]  # type: ignore[attr-defined]
    return ast.unparse(tree)


def test_make_controller_names_no_law_and_no_option():
    assert names_in(without_docstrings(TUNING.read_text())) == set()


def test_the_scan_sees_a_law_or_an_option_named():
    assert names_in('if spec.law == "cascade":\n    pass') == {"cascade"}
    assert names_in("x = spec.integral") == {"integral"}
    assert names_in("f(hold=True)") == {"hold"}
    assert names_in('k = "dq_smc_i_ff"') == {"dq_smc_i_ff"}
    assert names_in('if spec.rho_plan != "loss_aware": pass') == {"rho_plan", "loss_aware"}
    assert names_in(without_docstrings('def f():\n    """cascade"""\n    return 1')) == set()


def test_every_law_is_built_by_its_own_file():
    for law, entry in LAW_TABLE.items():
        module = entry.build.__module__
        assert module == f"flatstep.control.{law}" and entry.build.__name__ == "from_spec"


def test_what_an_option_needs_is_declared_with_it():
    assert {n for n, o in OPTIONS.items() if "torques" in o.needs} == {"feedforward"}
    assert ControllerSpec("dq_smc", integral=True).needs() == {"control_period"}
    assert ControllerSpec("cascade", feedforward=True).needs() == {"control_period", "torques"}
    assert ControllerSpec("smc").needs() == set()


def test_a_context_without_a_period_is_refused_by_a_law_that_needs_one():
    ctx = BuildContext(fs.MotorParams.preset("paper"), fs.PAPER_PLAN, "ideal")
    with pytest.raises(ValueError, match="control_period"):
        spec_module.ControllerSpec("cascade").build(ctx)
    assert type(ControllerSpec("smc").build(ctx)) is fs.FlatnessSMC
