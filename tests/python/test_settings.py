"""The module's keyword defaults are the schemas' (`quijibo settings`, util/settings.h): every keyword
of a stage function that names a setting of its section has that setting's default, and a value outside
the setting's range is refused with the range."""
import ast
import re

import pytest

import quijibo
from conftest import cli_json

# Each function and the section of `quijibo settings` its keywords belong to.
SECTIONS = {"energy": "energy", "mesh": "mesh", "optimize": "optimizer", "target": "target",
            "initial_guess": "initial", "modulus": "modulus", "portal": "portal"}


def keyword_defaults(function):
    """{name: default} of the keywords with a default in a pybind11 function's signature line."""
    line = function.__doc__.strip().splitlines()[0]
    inside = line[line.index("(") + 1:line.rindex(")")]
    parts, depth, start = [], 0, 0
    for i, c in enumerate(inside):
        depth += c in "([{"
        depth -= c in ")]}"
        if c == "," and depth == 0:
            parts.append(inside[start:i])
            start = i + 1
    parts.append(inside[start:])
    defaults = {}
    for part in parts:
        m = re.match(r"\s*(\w+)\s*:[^=]*=\s*(.+?)\s*$", part)
        if m:
            try:
                defaults[m.group(1)] = ast.literal_eval(m.group(2))
            except (ValueError, SyntaxError):
                pass  # None or an object: not a setting's default
    return defaults


@pytest.fixture(scope="module")
def settings():
    return cli_json("settings")


def test_every_keyword_default_is_the_schemas(settings):
    checked = 0
    for name, section in SECTIONS.items():
        entries = {}
        for s in settings[section]:
            entries.setdefault(s["key"], s)  # the first entry of a key is the one a face binds
        for key, value in keyword_defaults(getattr(quijibo, name)).items():
            if key in entries and entries[key]["default"] is not None:
                assert value == entries[key]["default"], (name, key, value, entries[key]["default"])
                checked += 1
    # energy's eleven settings and mesh's resolution and iterations at least: a signature the parser
    # no longer reads fails here instead of checking nothing.
    assert checked >= 13


def test_the_energy_keywords_are_exactly_its_settings(settings):
    keys = {s["key"] for s in settings["energy"]}
    assert set(keyword_defaults(quijibo.energy)) == keys


def test_values_outside_a_range_are_refused_with_the_range(settings, tiny_case):
    m, grid = tiny_case["rational_map"], tiny_case["grid"]
    calls = {"energy": lambda **kw: quijibo.energy(m, grid, **kw),
             "optimizer": lambda **kw: quijibo.optimize(grid, m, **kw),
             "mesh": lambda **kw: quijibo.mesh(m, **kw)}
    refused = 0
    for section, call in calls.items():
        for s in settings[section]:
            if s["type"] != "integer" or "lo" not in s or "/" in s["key"]:
                continue
            with pytest.raises(quijibo.Error) as e:
                call(**{s["key"]: int(s["lo"]) - 1})
            assert f"/{s['key']}: expected an integer in {s['range']}" in str(e.value), (section, s["key"], str(e.value))
            refused += 1
    assert refused >= 6
