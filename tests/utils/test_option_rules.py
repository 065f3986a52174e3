"""Option rules (refpo_warp.utils.option_rules): every option has one, the resolver and the constructors apply the same
one."""

import dataclasses

import pytest
import yaml

from refpo_warp.config.classes import POSITIONAL, class_defaults, resolve_class
from refpo_warp.config.resolve import resolve_config
from refpo_warp.config.run_options import NOT_RULED, RUN_RULES, SECTIONS
from refpo_warp.config.saved import fixed_changes
from refpo_warp.envs.registry import get_task, list_tasks
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_field import SECTION, UNSET
from refpo_warp.utils.option_rules import Check, Flag, Int, ListOf, OneOf, Real
from refpo_warp.utils.options import rules_for
from refpo_warp.utils.paths import PACKAGED_CONFIG_DIR as CONFIG_DIR

# Constructor arguments rsl_rl passes itself (never a config option).
_PASSED_BY_RSL_RL = {"device", "multi_gpu_cfg"}


def _constructor_options(cls) -> set[str]:
    """The options of a class: its Options fields and its constructor chain's keyword parameters."""
    return set(class_defaults(f"{cls.__module__}:{cls.__qualname__}"))


def _selected_classes():
    """(section, class) for every class_name an actor, critic or algorithm section of any config file selects."""
    found = set()

    def walk(node):
        if isinstance(node, dict):
            for key, value in node.items():
                if key in ("actor", "critic", "algorithm") and isinstance(value, dict) and "class_name" in value:
                    found.add((key, value["class_name"]))
                walk(value)
        elif isinstance(node, list):
            for item in node:
                walk(item)

    for path in sorted(CONFIG_DIR.rglob("*.yaml")):
        walk(yaml.safe_load(path.read_text()))
    classes = {(section, resolve_class(name)) for section, name in found}
    return sorted(classes, key=lambda sc: (sc[0], sc[1].__name__))


@pytest.mark.parametrize("section,cls", list(_selected_classes()), ids=lambda x: getattr(x, "__name__", x))
def test_every_constructor_option_has_a_rule(section, cls):
    options = _constructor_options(cls) - set(POSITIONAL[section]) - _PASSED_BY_RSL_RL
    missing = sorted(options - set(rules_for(cls)))
    assert not missing, (
        f"{cls.__name__} options without a rule (declare each with option(default, rule, doc)): {missing}"
    )


@pytest.mark.parametrize("task", list_tasks())
def test_every_env_option_has_a_rule(task):
    cfg_class = get_task(task).env_class().cfg_class
    missing = sorted({f.name for f in dataclasses.fields(cfg_class)} - set(rules_for(cfg_class)))
    assert not missing, (
        f"{cfg_class.__name__} fields without a rule (declare each with option(default, rule, doc)): {missing}"
    )


def test_every_run_option_has_a_rule_and_its_default_in_its_field():
    """Each field of the run options is a ruled option or a section; default.yaml sets none of them (one default, in
    the field), only the networks' shared settings."""
    for prefix, options in SECTIONS.items():
        for f in dataclasses.fields(options):
            if SECTION not in f.metadata:
                assert f"{prefix}{f.name}" in RUN_RULES, f"{prefix}{f.name} has no rule"
                assert f.default is not UNSET, f"{prefix}{f.name} has no default of its own"
    assert set(NOT_RULED) == {"env", "actor", "critic", "algorithm", "video", "eval.env"}
    default_yaml = yaml.safe_load((CONFIG_DIR / "default.yaml").read_text())
    assert set(default_yaml) <= {"actor", "critic", "algorithm"}, "a run option's default belongs in its field"


def test_a_saved_config_lists_the_run_options_in_their_fields_order():
    """config.yaml's keys in the order the fields stand, the sections of other classes' options among them (sweeps
    compare saved files byte for byte)."""
    cfg = resolve_config(["task=dmc_cheetah_run", "algo=ppo"], device_type="cpu")
    assert list(cfg) == [
        "task", "algo", "seed", "device", "torch_threads", "num_envs", "total_env_steps", "max_iterations", "run_dir",
        "resume",
        "stop_after_iterations", "stop_after_minutes", "verbose", "notice", "env", "init_from",
        "critic_warmup_iterations", "clone_normalizer", "config_dir", "runner", "actor", "critic", "algorithm",
        "video", "pretrain", "eval",
    ]  # fmt: skip
    assert list(cfg["eval"])[:5] == ["at_end", "flow_steps", "num_envs", "env", "max_steps"]
    assert list(cfg["critic"])[:2] == ["class_name", "obs_normalization"]  # default.yaml's order


@pytest.mark.parametrize(
    "rule,value,expected",
    [
        (Int(1, 10), 1, 1),
        (Int(1, 10), 10.0, 10),  # a whole float is an integer
        (Real(0, 1, lo_open=True), 3e-4, 3e-4),
        (Real(0, 1), 1, 1.0),
        (OneOf("a", "b"), "b", "b"),
        (OneOf(None, "a"), None, None),
        (ListOf(Int(1, 5), min_len=2, max_len=2), (1, 5), [1, 5]),
        (Int(2, 8, multiple_of=2), 8, 8),
        (Flag(), False, False),
    ],
)
def test_rules_accept_and_normalise(rule, value, expected):
    got = rule.check("k", value)
    assert got == expected and type(got) is type(expected)


@pytest.mark.parametrize(
    "rule,value,message",
    [
        (Int(1, 10), 0, "k=0 is invalid: out of range; expected an integer in [1, 10]"),
        (Int(1, 10), 11, "expected an integer in [1, 10]"),
        (Int(1, 10), 2.5, "not a whole number"),
        (Int(1, 10), True, "k=true is invalid"),
        (Int(1, 10), None, "k=null is invalid"),
        (Real(0, 1, lo_open=True), 0.0, "expected a number in (0, 1]"),
        (Real(0, None, lo_open=True), -1, "expected a number > 0"),
        (Real(0, 1), float("nan"), "not a finite number"),
        (Real(0, 1), float("inf"), "not a finite number"),
        (Real(0, 1), "fast", "k='fast' is invalid"),
        (OneOf("a", "b"), "c", "expected one of 'a', 'b'"),
        (ListOf(Int(1, 5)), [], "0 items"),
        (ListOf(Int(1, 5)), [1, 0], "k[1]=0 is invalid"),
        (Int(2, 8, multiple_of=2), 7, "not a multiple of 2"),
        (Flag(), "yes", "expected true or false"),
    ],
)
def test_rules_refuse_with_key_and_valid_range(rule, value, message):
    with pytest.raises(ConfigError) as err:
        rule.check("k", value)
    assert message in str(err.value)


def test_constructor_and_resolver_apply_the_same_rule():
    from refpo_warp.algorithms import ReFPO
    from refpo_warp.tasks.gridworld.env import GridWorldCfg

    with pytest.raises(ConfigError, match=r"algorithm\.num_mc_samples=0 is invalid.*\[1, 1024\]"):
        resolve_config(["task=gridworld", "algorithm.num_mc_samples=0"])
    with pytest.raises(ConfigError, match=r"ReFPO\.num_mc_samples=0 is invalid.*\[1, 1024\]"):
        ReFPO(None, None, None, num_mc_samples=0)  # refused before any argument is used
    with pytest.raises(ConfigError, match=r"env\.size=2 is invalid.*\[5, 100,000\]"):
        GridWorldCfg(size=2)
    with pytest.raises(ConfigError, match=r"ReFPO\.learning_rate=-1"):  # an inherited (rsl_rl PPO) rule
        ReFPO(None, None, None, learning_rate=-1)


def test_a_bad_constructor_argument_is_refused_before_it_is_used():
    from refpo_warp.algorithms import FlowGRPO

    with pytest.raises(ConfigError, match=r"FlowGRPO\.noise_level=-1 is invalid"):
        FlowGRPO(None, None, None, noise_level=-1)  # before its actor check


def test_custom_rule_gets_the_key():
    rule = Check(lambda key, v: v if v % 2 else (_ for _ in ()).throw(ConfigError(f"{key} must be odd")), "odd")
    assert rule.check("x.y", 3) == 3
    with pytest.raises(ConfigError, match=r"x.y must be odd"):
        rule.check("x.y", 4)


def test_resume_fixes_the_networks_but_frees_sampling_and_training_options():
    saved = resolve_config(["task=gridworld"])
    changed = resolve_config(
        [
            "task=gridworld",
            "actor.num_flow_steps=3",
            "algorithm.learning_rate=1e-4",
            "num_envs=8",
            "actor.hidden_dims=[8]",
            "critic.activation=tanh",
        ]
    )
    assert [c.split(":")[0] for c in fixed_changes(saved, changed, get_task("gridworld"))] == [
        "actor.hidden_dims",
        "critic.activation",
    ]
    assert fixed_changes(saved, resolve_config(["task=gridworld"]), get_task("gridworld")) == []
