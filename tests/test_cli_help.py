"""Every "(default: X)" in the command's help says the value the command uses.

The test walks every parser and subparser of ``relightnet`` and compares each help text's
"(default: X)" with the option's argparse default, or, for an option whose default is resolved when
the command runs (argparse default None), with the value it is resolved to (:data:`RESOLVED`).
"""

import argparse
import re

import pytest

from relightnet.cli import build_parser


def _synth(name):
    import dataclasses

    from relightnet.data.config import SynthConfig

    return lambda: {f.name: f.default for f in dataclasses.fields(SynthConfig)}[name]


def _const(module, name):
    import importlib

    return lambda: getattr(importlib.import_module(module), name)


#: (command, option) -> the value an option with argparse default None is given when the command runs.
RESOLVED = {
    ("synth", "--res"): _synth("res"),
    ("synth", "--seed"): _synth("seed"),
    ("synth", "--n-dirs"): _synth("n_dirs"),
    ("synth", "--shard-size"): _synth("shard_size"),
    ("synth", "--lmax"): _synth("lmax"),
    ("synth", "--cpus-per-task"): _const("relightnet._cli.synth", "CPUS_PER_TASK"),
    ("synth", "--n"): _const("relightnet._cli.synth", "PREVIEW_ROWS"),
    ("estimate-light", "--fov"): _const("relightnet._cli.model", "PLATE_FOV"),
    ("avatar", "--motion"): _const("relightnet._cli.avatar", "DEFAULT_MOTION"),
    ("*", "--max-pixels"): _const("relightnet.io.limits", "DEFAULT_MAX_PIXELS"),  # with $RELIGHTNET_MAX_PIXELS unset
}


def _options(parser, path=()):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _options(sub, (*path, name))
        elif action.help and action.help is not argparse.SUPPRESS and action.option_strings:
            yield " ".join(path), action


def _spellings(value) -> set[str]:
    if isinstance(value, bool):
        return {"on" if value else "off"}
    if isinstance(value, float):
        return {f"{value:g}", str(value)}
    if isinstance(value, int):
        return {str(value), f"{value:,}"}
    return {str(value)}


def _stated(action) -> list[str]:
    text = action.help % {**vars(action), "prog": "relightnet"} if "%" in action.help else action.help
    return [m.group(1) for m in re.finditer(r"\(default: ([^);]*)", text)]


CASES = [(cmd, a) for cmd, a in _options(build_parser()) if _stated(a)]


@pytest.mark.parametrize("command,action", CASES, ids=[f"{c} {a.option_strings[-1]}" for c, a in CASES])
def test_a_stated_default_is_the_default(command, action):
    key = (command, action.option_strings[0])
    for stated in _stated(action):
        resolve = RESOLVED.get(key) or RESOLVED.get(("*", key[1]))
        if resolve is not None:
            value = resolve()
        elif action.default is None or action.default is False:
            # no value: the help describes what happens without the option, in words
            assert not stated[:1].isdigit(), f"{key}: help says default {stated!r}, argparse has {action.default!r}"
            continue
        else:
            value = action.default
        assert any(stated == s or stated.startswith((s + ":", s + ",", s + " ")) for s in _spellings(value)), \
            f"{key}: help says default {stated!r}, the command uses {value!r}"


def test_every_command_states_some_default():
    assert len({c for c, _ in CASES}) > 20 and len(CASES) > 100
