"""The option schema: one declaration per option, and every interface made from it."""

import ast
import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tt_mujoco import config, gym_env, run, schema
from tt_mujoco.cliargs import BadInputError
from tt_mujoco.schema import Option, Schema, choice, number, option
from tt_mujoco.sim import SCHEMA, Scenario
from tt_mujoco.sweep import options as sweep_options
from tt_mujoco.sweep import runs as sweep_runs


@dataclasses.dataclass
class TyreScenario(Scenario):
    """A scenario with one more option, as a contributor would add it: one field."""

    tyre_model: str = option(
        "linear",
        choice("linear", "pacejka"),
        "the tyre model",
        choices=("linear", "pacejka"),
    )
    tyre_stiffness: float = option(
        8.0, number(0, low_open=True), "cornering stiffness", unit="N/rad"
    )


TYRE_SCHEMA = Schema.of(TyreScenario)


def test_a_new_field_reaches_the_command_line_files_sweeps_and_the_gym_env(tmp_path):
    extra = {"tyre_model": "pacejka", "tyre_stiffness": 12.5}
    run_schema = TYRE_SCHEMA + run.OUTPUTS
    # The command line: its options, help and checks.
    parser = run.build_parser(run_schema)
    assert "--tyre-model {linear,pacejka}" in parser.format_help()
    assert "[N/rad]" in parser.format_help()
    given = run.options_from_argv(
        ["--tyre-model", "pacejka", "--tyre-stiffness", "12.5"], run_schema
    )
    assert {k: given[k] for k in extra} == extra
    with pytest.raises(BadInputError, match=r"'pacejk' is not allowed.*did you mean 'pacejka'"):
        run.options_from_argv(["--tyre-model", "pacejk"], run_schema)
    # A scenario file (and the command line over it).
    file = tmp_path / "tyre.toml"
    file.write_text('tyre_model = "pacejka"\ntyre-stiffness = 12.5\n')
    assert config.read_options(config.load_config(file), file, run_schema) == extra
    merged = run.options_from_argv(["--config", str(file), "--tyre-stiffness", "3"], run_schema)
    assert (merged["tyre_model"], merged["tyre_stiffness"]) == ("pacejka", 3.0)
    with pytest.raises(ValueError, match=r"tyre\.toml': unknown key 'tyre_mode'.*'tyre_model'"):
        config.read_options({"tyre_mode": "linear"}, file, run_schema)
    # A sweep's options.
    assert sweep_options.convert("tyre_stiffness", "12.5", TYRE_SCHEMA, typed=False) == 12.5
    assert sweep_options.convert("tyre_stiffness", 12.5, TYRE_SCHEMA) == 12.5
    with pytest.raises(sweep_options.BadSpecError, match="tyre_stiffness='-1' is not allowed"):
        sweep_options.convert("tyre_stiffness", "-1", TYRE_SCHEMA, typed=False)
    values = sweep_runs.scenario_values({"tyre_model": "pacejka", "seed": 3}, TYRE_SCHEMA)
    assert values == {"tyre_model": "pacejka", "seed": 3}
    # The Gym env's keyword arguments.
    assert gym_env.scenario_overrides({"tyre_model": "pacejka"}, TYRE_SCHEMA) == {
        "tyre_model": "pacejka"
    }
    with pytest.raises(ValueError, match="did you mean 'tyre_model'"):
        gym_env.scenario_overrides({"tyre_modle": "pacejka"}, TYRE_SCHEMA)
    # Every route's values make the scenario, and its file form repeats it.
    scenario = TyreScenario(**{k: given[k] for k in TYRE_SCHEMA.names})
    assert (scenario.tyre_model, scenario.tyre_stiffness) == ("pacejka", 12.5)
    written = TYRE_SCHEMA.file_form(scenario.to_dict())
    assert TYRE_SCHEMA.values(written, "") == {
        k: v for k, v in scenario.to_dict().items() if v is not None
    }


def test_every_scenario_field_is_an_option_with_help():
    fields = [f.name for f in dataclasses.fields(Scenario)]
    assert list(SCHEMA.names) == fields
    for opt in SCHEMA.options:
        assert opt.help and opt.parse is not None, opt.name
        assert opt.default_value() == getattr(Scenario(), opt.name) or opt.name == "control_dt"


def _spellings(tree: ast.AST) -> set[str]:
    """The option spellings a module's code uses: flags in its strings, fields it reads or
    sets as attributes or keyword arguments (docstrings left out)."""
    docstrings = {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Module | ast.FunctionDef | ast.ClassDef)
        and node.body
        and isinstance(node.body[0], ast.Expr)
        and isinstance(node.body[0].value, ast.Constant)
    }
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            if id(node) not in docstrings:
                found.add(node.value)
        elif isinstance(node, ast.Attribute):
            found.add(node.attr)
        elif isinstance(node, ast.keyword) and node.arg:
            found.add(node.arg)
    return found


def test_the_routes_keep_no_mapping_of_their_own():
    # No interface spells out a scenario option: each comes from the schema. (The sweep's
    # per-trailer options and its "on"/"off" are its own spelling, not a field's.)
    root = Path(run.__file__).parent
    flags = set()
    for opt in SCHEMA.options:
        flags |= {*opt.cli_flags, *(f for f, _ in opt.consts)}
    # The fields with names of their own (a report may read ``scenario.plant`` or
    # ``result.metrics``; no interface should need ``noise_snr_db`` or ``path_feedback``).
    fields = {o.name for o in SCHEMA.options if "_" in o.name}
    for module in ("run.py", "config.py", "sweep/runs.py", "sweep/options.py", "gym_env.py"):
        # The env steps the scenario itself (its control period, a reset's phi0): fields it
        # reads are its work, not a mapping; its keyword arguments go through the schema.
        spellings = flags if module == "gym_env.py" else flags | fields
        used = _spellings(ast.parse((root / module).read_text())) & spellings
        assert not used, (module, sorted(used))


@pytest.mark.parametrize(
    ("parse", "value", "expected"),
    [
        (number(0, low_open=True), "2.5", 2.5),
        (number(0, low_open=True), 3, 3.0),
        (number(0, integer=True), "7", 7),
        (number(0, integer=True), 7.0, 7),
        (number(optional=True), "none", None),
        (number(0, words=("actuator",)), "Actuator", "actuator"),
        (schema.boolean, "off", False),
        (schema.boolean, True, True),
        (schema.spec_list(schema.text), "a; b", ["a", "b"]),
        (schema.spec_list(schema.text), "none", []),
        (schema.optional_table(number()), "on", {}),
        (schema.optional_table(number()), False, None),
        (schema.optional_table(number()), {"k_y": "2"}, {"k_y": 2.0}),
        (schema.table(number(), ("a", "b")), {"a": 1}, {"a": 1.0}),
    ],
)
def test_parsers_convert_text_and_toml_values_alike(parse, value, expected):
    assert parse(value, "x") == expected
    assert parse(parse(value, "x"), "x") == expected  # a converted value passes unchanged


@pytest.mark.parametrize(
    ("parse", "value", "message"),
    [
        (number(0, low_open=True), "0", r"x='0' is not allowed: it must be a finite number > 0"),
        (number(1, 8, integer=True), 9, r"x=9 is not allowed: it must be an integer in \[1, 8\]"),
        (number(), float("nan"), "it must be a finite number"),
        (number(), True, "it must be a finite number"),
        (choice("linear", "pacejka"), "lin", r"use one of 'linear', 'pacejka'"),
        (schema.boolean, "maybe", "use true or false"),
        (schema.boolean, 1, "use true or false"),  # a number is no truth value (text "1" is)
        (schema.boolean, 0.0, "use true or false"),
        (schema.text, "  ", "non-empty string"),
        (schema.table(number(), ("a",)), {"b": 1}, r"x: 'b' is not allowed.*use one of a"),
        (schema.optional_table(number()), "sometimes", "use on"),
    ],
)
def test_parsers_refuse_naming_the_value_and_what_is_allowed(parse, value, message):
    with pytest.raises(ValueError, match=message):
        parse(value, "x")


def test_keys_aliases_and_negated_switches():
    values = SCHEMA.values(
        {"noise-snr": 20, "no_reverse": True, "no_disturbance": True, "param.Mr": 7.5}, "here"
    )
    assert values == {
        "noise_snr_db": 20.0,
        "reverse": False,
        "disturbance": "none",
        "params": {"Mr": 7.5},
    }
    with pytest.raises(ValueError, match="name the same option"):
        SCHEMA.values({"noise_snr": 1, "noise_snr_db": 2}, "here")
    with pytest.raises(ValueError, match=r"here: unknown key 'tarjet' \(did you mean 'target'"):
        SCHEMA.values({"tarjet": "static"}, "here")
    with pytest.raises(ValueError, match="path_feedback=off contradicts k_y"):
        SCHEMA.values({"path_feedback": "off", "path_feedback.k_y": 2}, "")


def test_tables_merge_key_by_key_and_lists_replace():
    merged = SCHEMA.merged(
        {"params": {"Mr": 7.0, "Ird": 0.02}, "faults": [{"kind": "dropout", "t": 1.0}]},
        {"params": {"Mr": 8.0}, "faults": []},
    )
    assert merged["params"] == {"Mr": 8.0, "Ird": 0.02}
    assert merged["faults"] == []
    assert merged["hitch_feedback"] == {} and merged["seed"] == 0


def test_file_form_writes_off_tables_as_false_and_skips_none_defaults():
    form = SCHEMA.file_form(Scenario(hitch_feedback=None).to_dict())
    assert form["hitch_feedback"] is False
    assert "duration" not in form and "path_feedback" not in form
    assert json.loads(json.dumps(form)) == form  # plain data


def test_the_options_page_lists_every_option():
    table = SCHEMA.markdown_table()
    for opt in SCHEMA.options:
        assert f"`{opt.name}`" in table
    assert "`--noise-snr-db`" in table and "dB" in table


def test_a_bad_form_is_refused():
    with pytest.raises(ValueError, match="form='flag' is not allowed"):
        Option("x", 1, "help", number(), form="flag")


def _integer_options():
    from tt_mujoco import run

    found = []
    for opt in (SCHEMA + run.OUTPUTS).options:
        try:
            value = opt.parse("3", opt.name)
        except (ValueError, TypeError):
            continue
        if type(value) is int:
            found.append(opt)
    return found


@pytest.mark.parametrize("opt", _integer_options(), ids=lambda o: o.name)
def test_every_integer_option_takes_only_what_a_toml_file_holds(opt):
    """What an option takes lands in config.toml (and a sweep's files), whose integers are
    64-bit: a larger one would be written as a file no strict TOML reader reads back."""
    from tt_mujoco.schema_values import TOML_INT_MAX

    for too_large in (str(TOML_INT_MAX + 1), TOML_INT_MAX + 1, float(2**64)):
        with pytest.raises(ValueError, match=r"is not allowed: it must be an integer in \["):
            opt.parse(too_large, opt.name)


def test_integer_options_are_found_and_a_seed_takes_the_largest():
    from tt_mujoco.schema_values import TOML_INT_MAX

    assert {"seed", "trailers"} <= {o.name for o in _integer_options()}
    assert SCHEMA["seed"].parse(str(TOML_INT_MAX), "seed") == TOML_INT_MAX


def _typed_options():
    """Every option (the scenario's and the outputs') with a text that its parser turns into
    a number or true/false: the text, and what it parses to."""
    found = []
    for opt in (SCHEMA + run.OUTPUTS).options:
        for text in ("true", "1", "0.5", "2", "20"):
            try:
                value = opt.parse(text, opt.name)
            except (ValueError, TypeError):
                continue
            if isinstance(value, bool | int | float):
                found.append(pytest.param(opt, text, value, id=opt.name))
                break
    return found


@pytest.mark.parametrize(("opt", "text", "value"), _typed_options())
def test_text_for_a_number_or_a_truth_value_is_taken_from_the_command_line_only(
    opt, text, value, tmp_path
):
    """The command line (and a sweep's command-line axes) gives text; a TOML file, a sweep
    file, the Python API and the Gym env give typed values, so ``video = "yes"`` there is a
    mistake, refused naming the key, where ``--video yes`` is text to read."""
    both = SCHEMA + run.OUTPUTS
    assert both.values({opt.name: text}, "", typed=False)[opt.name] == value
    assert both.values({opt.name: value}, "")[opt.name] == value
    refused = rf"{opt.name}='{text}' is not allowed: it is text where"
    with pytest.raises(ValueError, match=refused):
        both.values({opt.name: text}, "")
    toml = tmp_path / "scenario.toml"
    toml.write_text(f'{opt.name} = "{text}"\n')
    with pytest.raises(ValueError, match=f"config file.*{refused}"):
        config.read_options(config.load_config(toml), toml, both)
    if opt.name not in SCHEMA.names:
        return
    with pytest.raises(ValueError, match=refused):
        Scenario(**{opt.name: text}).validate()
    with pytest.raises(ValueError, match=refused):
        gym_env.scenario_overrides({opt.name: text})
    if opt.axis:
        assert sweep_options.convert(opt.name, text, typed=False) == value
        with pytest.raises(sweep_options.BadSpecError, match=refused):
            sweep_options.convert(opt.name, text)


def test_typed_options_are_found_and_tables_and_switches_are_checked_too():
    names = {p.values[0].name for p in _typed_options()}
    assert {"seed", "duration", "video", "reverse", "noise_snr_db", "eta"} <= names
    with pytest.raises(ValueError, match=r"here: gains.k1_v='5' is not allowed: it is text"):
        SCHEMA.values({"gains": {"k1_v": "5"}}, "here")
    with pytest.raises(ValueError, match=r"here: no_video='yes' is not allowed: it is text"):
        (SCHEMA + run.OUTPUTS).values({"no_video": "yes"}, "here")
    with pytest.raises(ValueError, match=r"here: no_video=1 is not allowed: use true or false"):
        (SCHEMA + run.OUTPUTS).values({"no_video": 1}, "here")
    # JSON is typed as TOML is: --gains '{"k1_v": "5"}' is the same mistake
    with pytest.raises(ValueError, match=r"gains.k1_v='5' is not allowed: it is text"):
        SCHEMA["gains"].parse('{"k1_v": "5"}', "gains")
    assert SCHEMA["gains"].parse('{"k1_v": 5}', "gains") == {"k1_v": 5.0}
    # Text an option keeps as text ("none" where TOML has no null, a word) stays allowed.
    assert SCHEMA.values({"eta": "same_path", "duration": "none"}, "")["duration"] is None


@pytest.mark.parametrize("opt", _integer_options(), ids=lambda o: o.name)
def test_an_integer_option_reads_its_text_as_a_toml_file_holds_it(opt):
    """A whole float is taken as TOML's ``3.0`` is (so ``--seed 3.0`` and ``seed = 3.0`` run
    the same), read exactly; text that is no ASCII number (``int("３")`` is 3 in Python) is
    refused, and a huge exponent is refused without being written out."""
    for spelling in ("3", "3.0", "3e0", " 3 ", 3.0):
        assert opt.parse(spelling, opt.name) == 3
    for bad in ("３", "3.5", "0x3", "nan", "1e999999999", "9" * 5000):
        with pytest.raises(ValueError, match="is not allowed: it must be an integer"):
            opt.parse(bad, opt.name)


def test_every_text_of_numbers_is_read_by_one_reader():
    """The specs written as text (wind, terrain, ground patches, faults, a sweep's numbers and
    ranges) read their numbers as the option schema does: ASCII, exact, finite."""
    from tt_mujoco.schema_values import number_text
    from tt_mujoco.sim.parts.faults import parse_fault
    from tt_mujoco.sim.parts.ground import parse_patch
    from tt_mujoco.sim.parts.terrain import parse_terrain
    from tt_mujoco.sim.parts.wind import parse_wind
    from tt_mujoco.sweep import spec

    assert number_text("1_0.5") == 10.5 and number_text("１") is None
    assert number_text("9007199254740993.0", integer=True) == 9007199254740993
    refusals = [
        (parse_wind, "８:90"),
        (parse_terrain, "slope:５"),
        (parse_patch, "band:0:１:0.5"),
        (parse_fault, "dropout:t=１"),
        (lambda text: sweep_options.as_number("gain.k1_v", text), "１"),
        (lambda text: spec.parse_item(f"seed=range:0:{text}"), "３"),
    ]
    for parse, text in refusals:
        with pytest.raises(ValueError, match="not"):
            parse(text)


def _typed_defaults():
    for opt in SCHEMA.options:
        if isinstance(opt.default, bool):
            yield pytest.param(opt, np.bool_(opt.default), id=opt.name)
        elif isinstance(opt.default, int):
            yield pytest.param(opt, np.int64(opt.default), id=opt.name)
        elif isinstance(opt.default, float):
            yield pytest.param(opt, np.float64(opt.default), id=opt.name)


@pytest.mark.parametrize(("opt", "numpy_value"), list(_typed_defaults()))
def test_every_number_or_truth_option_takes_a_numpy_scalar_as_its_value(opt, numpy_value):
    """The Python API is driven from NumPy (``for d in np.linspace(...)``): a NumPy scalar is
    its value, made a Python one, as a truth value already was."""
    parsed = opt.parse(numpy_value, opt.name)
    assert parsed == opt.parse(opt.default, opt.name)
    assert type(parsed) is type(opt.parse(opt.default, opt.name))
    scenario = Scenario(**{opt.name: numpy_value})
    scenario.validate()
    assert type(getattr(scenario, opt.name)) is type(parsed)


#: Anything a command line, a file, the API or a sweep might hand an option's parser.
_ANY_VALUE = st.one_of(
    st.text(max_size=20),
    st.from_regex(r"\s*-?[0-9]{0,25}(\.[0-9]{0,5})?(e-?[0-9]{1,3})?\s*", fullmatch=True),
    st.integers(),
    st.floats(allow_nan=True, allow_infinity=True),
    st.booleans(),
    st.none(),
    st.lists(st.integers(), max_size=3),
    st.dictionaries(st.text(max_size=5), st.integers(), max_size=2),
    st.floats(allow_nan=True).map(np.float64),
    st.integers(min_value=-(2**63), max_value=2**63 - 1).map(np.int64),
)


@pytest.mark.parametrize("opt", SCHEMA.options, ids=lambda o: o.name)
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(value=_ANY_VALUE)
def test_every_parser_takes_a_value_or_refuses_it_naming_the_option(opt, value):
    """Whatever it is given, an option's parser returns a value or raises ValueError naming
    the option: never another exception, never a non-finite number taken."""
    try:
        parsed = opt.parse(value, opt.name)
    except ValueError as err:
        assert opt.name in str(err) or "is not allowed" in str(err), err
        assert "np." not in str(err), err  # the value as the number it is, not NumPy's repr
        return
    if isinstance(parsed, float):
        assert np.isfinite(parsed), parsed
