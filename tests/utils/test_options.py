"""Options declared once (refpo_warp/utils/options.py): an option's field is its default, its rule and its doc for the
resolver, --explain, the docs' tables and the constructor alike."""

from dataclasses import dataclass

import pytest

from refpo_warp.algorithms import ReFPO
from refpo_warp.algorithms.refpo import TauSampling
from refpo_warp.config.classes import class_defaults
from refpo_warp.config.resolve import resolve_config
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_rules import Int, OneOf, Real
from refpo_warp.utils.options import declared_options, option, option_values, rules_for


def test_every_declared_option_has_a_rule_and_a_doc():
    from refpo_warp import algorithms

    for cls in (c for c in vars(algorithms).values() if isinstance(c, type)):
        for name, found in declared_options(cls).items():
            assert found.rule is not None and found.doc, f"{cls.__name__}.{name}: declare its rule and doc"


def test_a_field_gives_a_base_option_another_default_and_keeps_its_rule():
    declared = declared_options(ReFPO)
    assert (declared["clip_param"].default, declared["clip_param"].owner) == (0.05, ReFPO)
    assert declared["clip_param"].rule is rules_for(ReFPO)["clip_param"]  # rsl_rl's PPO rule (rsl_rl_options.py)
    assert class_defaults("refpo_warp.algorithms:ReFPO")["clip_param"] == (0.05, ReFPO)
    assert declared["reward_scale"].owner.__name__ == "OnPolicyAlgorithm"
    with pytest.raises(ConfigError, match=r"algorithm.clip_param=0 is invalid.*a number in \(0, 10\]"):
        resolve_config({"task": "gridworld", "device": "cpu", "algorithm.clip_param": 0})


def test_choices_are_an_enums_values_and_stay_plain_strings():
    rule = OneOf(None, TauSampling)
    assert rule.choices == ("uniform", "discrete", "logit_normal", "uniform_inset") and rule.optional
    assert rule.check("k", TauSampling.LOGIT_NORMAL) == "logit_normal" and rule.check("k", None) is None
    with pytest.raises(ConfigError, match=r"k='gaussian' is invalid; expected null or one of 'uniform'"):
        rule.check("k", "gaussian")


def test_a_list_default_is_copied_for_every_reader():
    @dataclass(frozen=True)
    class Owner:
        sizes: list = option([1, 2], Real(), "sizes")

    first = declared_options(Owner)["sizes"].default
    first.append(3)
    assert declared_options(Owner)["sizes"].default == [1, 2]


def test_an_algorithms_options_are_typed_attributes_of_its_class():
    import typing

    hints = typing.get_type_hints(ReFPO, include_extras=False, localns={"TauSampling": TauSampling})
    assert hints["reflow_coef"] is float and hints["reward_scale"] is float  # its own and its base's


def test_a_subclass_field_replaces_its_bases_and_keeps_its_rule():
    class Base:
        a: int = option(0, Int(0, 1), "a")

    class Child(Base):
        a: int = option(1)
        b: str = option("x", OneOf("x", "y"), "b")

    values, rest = option_values(Child, {"b": "y", "other": 3})
    assert values == {"a": 1, "b": "y"} and rest == {"other": 3}
    assert declared_options(Child)["a"].doc == "a"
    with pytest.raises(ConfigError, match=r"Child\.a=2 is invalid"):
        option_values(Child, {"a": 2})
