"""Strict scenes: the mistakes users made, each refused in one line at the key written,
the unit slips warned about (and silenced on request), and a run without references
that says so instead of passing.

Every error names the file once, the key as a TOML path (``parameters.mu``), the value
as written and what is allowed; nothing runs on the model's built-in defaults.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest
from PIL import Image

from contact_fmu import cli
from contact_fmu.scenario import ScenarioError, discover, load
from contact_fmu.scenario import plot as scene_plot
from contact_fmu.scenario.labels import axis_label, axis_labels, metric_label
from contact_fmu.scenario.plausibility import G, PlausibilityWarning
from contact_fmu.scenario.schema import Metric

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "scenarios"

PARAMETERS = """[parameters]
mu = 0.3
Rx = 0.05
Ry = 0.10
k1 = 5.0e-13
k2 = 5.0e-13
kb = 3.2e-13
ks = 3.2e-13
M = 1.0
Iy = 8.333333333333335e-4
Vx0 = 5.6418958354775635
"""
# The paper's body (Fig. 13 set) under its load, 10 steps: a scene as users write one.
SCENE = (
    """name = "mini"
[model]
mode = "body"
[run]
stop_time = 1.0e-3
step = 1.0e-4
outputs = ["Tx", "Vx"]
"""
    + PARAMETERS
    + """[inputs]
P = 1000.0
My_ex = -0.5
"""
)


def _write(tmp_path: Path, text: str, name: str = "mini.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _refused(path: Path) -> str:
    """The error of loading ``path``: one line, naming the file once, at its start."""
    with pytest.raises(ScenarioError) as e:
        load(path)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith(f"{path}: ") and msg.count(str(path)) == 1, msg
    return msg


def _edit(old: str, new: str, text: str = SCENE) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


def _loads_quietly(path: Path):
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        return load(path)


def _warnings_of(path: Path) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PlausibilityWarning)
        load(path)
    return [str(w.message) for w in caught if issubclass(w.category, PlausibilityWarning)]


# ---- required sections and keys -----------------------------------------------------------
def test_a_scene_without_parameters_is_refused_not_run_on_built_in_defaults(tmp_path):
    """The user's scene ran a 1 kg body with Rx = 0.05 m, the FMU's defaults, to
    Vx = -524 m/s and passed: every physical parameter of the model must be given."""
    msg = _refused(_write(tmp_path, _edit(PARAMETERS, "")))
    assert "[parameters] mu, Rx, Ry, k1, k2, kb, ks, M, Iy, Vx0 is missing" in msg
    assert "no built-in defaults" in msg


def test_one_missing_parameter_is_named(tmp_path):
    msg = _refused(_write(tmp_path, _edit("M = 1.0\n", "")))
    assert "[parameters] M is missing: a body-mode scene with the layer law gives" in msg


def test_contact_mode_needs_no_body_parameters_and_the_halfspace_law_takes_mu_rx_from_its_table():
    """Contact mode has no body (M, Iy, Vx0); rail_creep's mu and Rx are in [halfspace]."""
    from contact_fmu.scenario.schema import required_parameters

    assert required_parameters(load(SCENARIOS / "sweep.toml").config) == (
        "mu", "Rx", "Ry", "k1", "k2", "kb", "ks"
    )  # fmt: skip
    assert required_parameters(load(SCENARIOS / "rail_creep.toml").config) == ()
    assert required_parameters(load(SCENARIOS / "rail_traction.toml").config) == (
        "M", "Iy", "Vx0"
    )  # fmt: skip
    assert "Iz" in required_parameters(load(SCENARIOS / "cornering.toml").config)


def test_a_scene_without_model_is_refused(tmp_path):
    msg = _refused(_write(tmp_path, _edit('[model]\nmode = "body"\n', "")))
    assert "[model] is missing" in msg


def test_a_model_without_mode_is_refused(tmp_path):
    msg = _refused(_write(tmp_path, _edit('mode = "body"\n', "")))
    assert "model.mode is missing: body | contact" in msg


def test_a_missing_time_grid_key_is_named(tmp_path):
    msg = _refused(_write(tmp_path, _edit("step = 1.0e-4\n", "")))
    assert "run.step is missing" in msg


def test_a_reference_without_tolerance_is_refused(tmp_path):
    text = SCENE + '[[reference]]\nfile = "r.csv"\nsource = "quasistationary"\n'
    msg = _refused(_write(tmp_path, text))
    assert "reference[0].tolerance is missing" in msg


# ---- declared types -----------------------------------------------------------------------
@pytest.mark.parametrize(
    ("value", "fragment"),
    [
        ('"0.9"', "parameters.mu = '0.9' is invalid: must be a number (a string is not a number"),
        ("true", "parameters.mu = True is invalid: must be a number (true/false is not a number)"),
        ("[0.3]", "parameters.mu = [0.3] is invalid: must be a number"),
    ],
)
def test_mu_must_be_a_number_not_a_string_or_a_bool(tmp_path, value, fragment):
    """mu = "0.9" was taken as 0.9 and mu = true as 1 (bool is an int in Python)."""
    msg = _refused(_write(tmp_path, _edit("mu = 0.3", f"mu = {value}")))
    assert fragment in msg, msg


def test_an_integer_parameter_refuses_a_float_and_a_bool(tmp_path):
    text = _edit('mode = "body"', 'mode = "body"\nphase = "transient"')
    msg = _refused(_write(tmp_path, _edit("Vx0 =", "nx = 32.5\nVx0 =", text)))
    assert "parameters.nx = 32.5 is invalid: must be an integer" in msg
    msg = _refused(_write(tmp_path, _edit("Vx0 =", "nx = true\nVx0 =", text)))
    assert "parameters.nx = True is invalid: must be an integer (true/false" in msg


@pytest.mark.parametrize(
    ("old", "new", "fragment"),
    [
        ("step = 1.0e-4", "step = true", "run.step = True is invalid: must be a finite number > 0"),
        ("stop_time = 1.0e-3", 'stop_time = "1 ms"', "run.stop_time = '1 ms' is invalid"),
        ("P = 1000.0", 'P = "1000"', "inputs.P = '1000' is invalid: must be a number"),
        ("P = 1000.0", "P = false", "inputs.P = False is invalid: must be a number"),
        ('mode = "body"', "mode = 1", "model.mode = 1 is invalid: must be one of ['body'"),
        ('outputs = ["Tx", "Vx"]', 'outputs = "Tx"', "run.outputs = 'Tx' is invalid"),
    ],
)
def test_a_value_of_the_wrong_type_is_refused_at_its_key(tmp_path, old, new, fragment):
    msg = _refused(_write(tmp_path, _edit(old, new)))
    assert fragment in msg, msg


def test_a_case_value_is_reported_in_its_case(tmp_path):
    text = SCENE + '[[cases]]\nname = "heavy"\nparameters = { M = "2" }\n'
    msg = _refused(_write(tmp_path, text))
    assert "cases['heavy'].parameters.M = '2' is invalid: must be a number (kg)" in msg
    text = SCENE + '[[cases]]\nname = "heavy"\ninputs = { P = { step = { time = "0" } } }\n'
    msg = _refused(_write(tmp_path, text))
    assert "cases['heavy'].inputs.P.step: 'time' = '0' must be a finite number" in msg


# ---- a variable in the wrong section ------------------------------------------------------
def test_an_output_under_parameters_is_reported_there_saying_where_it_belongs(tmp_path):
    """Tx under [parameters] was reported at cases.default.parameters.Tx."""
    msg = _refused(_write(tmp_path, _edit("mu = 0.3", "mu = 0.3\nTx = 3.0")))
    assert "parameters.Tx = 3.0: Tx is an output of this body-mode model, not a parameter" in msg
    assert "list it in run.outputs" in msg and "cases" not in msg


def test_an_output_with_an_initial_value_points_at_its_parameter(tmp_path):
    msg = _refused(_write(tmp_path, _edit("mu = 0.3", "mu = 0.3\nVx = 3.0")))
    assert "parameters.Vx = 3.0" in msg and "the parameter(s) Vx0" in msg


def test_an_input_under_parameters_belongs_in_inputs(tmp_path):
    msg = _refused(_write(tmp_path, _edit("mu = 0.3", "mu = 0.3\nFx_ex = 10.0")))
    assert "parameters.Fx_ex = 10.0: Fx_ex is an input of this body-mode model" in msg
    assert "it belongs in [inputs]" in msg


def test_a_parameter_under_inputs_belongs_in_parameters(tmp_path):
    msg = _refused(_write(tmp_path, _edit("P = 1000.0", "P = 1000.0\nmu = 0.3")))
    assert "inputs.mu = 0.3: mu is a parameter of this body-mode model, not an input" in msg
    assert "it belongs in [parameters]" in msg


def test_a_parameter_among_a_cases_inputs_belongs_in_its_parameters(tmp_path):
    msg = _refused(_write(tmp_path, SCENE + '[[cases]]\nname = "c"\ninputs = { Iy = 1e-3 }\n'))
    assert "cases['c'].inputs.Iy = 0.001: Iy is a parameter" in msg
    assert "it belongs in cases['c'].parameters" in msg


def test_a_parameter_among_the_outputs_is_named(tmp_path):
    msg = _refused(_write(tmp_path, _edit('outputs = ["Tx", "Vx"]', 'outputs = ["Tx", "mu"]')))
    assert "run.outputs = ['Tx', 'mu']: mu is a parameter of this body-mode model" in msg


def test_an_unknown_variable_lists_the_models_parameters(tmp_path):
    msg = _refused(_write(tmp_path, _edit("mu = 0.3", "mu = 0.3\nradius = 0.05")))
    assert "parameters.radius = 0.05: no FMU variable is called 'radius'" in msg
    assert "'Rx'" in msg


# ---- legal values the liftoff scene needs ---------------------------------------------------
def test_a_load_ramp_through_zero_is_legal_and_plausible(tmp_path):
    """P from 1000 N to 0 and back (lift-off): the schema checks types, not the range of
    an input (the FMU's variable ranges are the truth there); the largest load, 1000 N =
    102 M g, is plausible."""
    ramp = "P = [1000.0, { ramp = { start = 2e-4, duration = 3e-4, height = -1000 } }, "
    ramp += "{ ramp = { start = 6e-4, duration = 3e-4, height = 1000 } }]"
    scene = _loads_quietly(_write(tmp_path, _edit("P = 1000.0", ramp)))
    P = scene.cases[0].inputs["P"](scene.grid)
    assert P.min() == pytest.approx(0.0, abs=1e-9) and P[0] == 1000.0
    text = _edit("P = 1000.0", "P = [0, { step = { time = 0.0, height = 1000 } }]")
    scene = load(_write(tmp_path, text))  # integers are numbers too
    assert scene.cases[0].inputs["P"](scene.grid)[0] == 1000.0


# ---- plausibility ---------------------------------------------------------------------------
def test_shipped_scenes_give_no_plausibility_warning():
    paths = discover(SCENARIOS) + discover(SCENARIOS / "studies")
    assert len(paths) >= 10
    for path in paths:
        _loads_quietly(path)


def test_a_radius_in_mm_is_warned_about_and_accepted_on_request(tmp_path):
    """Rx = 300 (mm typed as m): 30 times the largest wheel's radius."""
    (msg,) = [
        m for m in _warnings_of(_write(tmp_path, _edit("Rx = 0.05", "Rx = 300"))) if "Rx" in m
    ]
    assert msg.startswith(f"{tmp_path / 'mini.toml'}: parameters.Rx = 300: a radius over 10 m")
    assert "typed in mm?" in msg and "\n" not in msg
    text = _edit("Rx = 0.05", "Rx = 300") + '[checks]\naccept = ["Rx"]\n'
    assert _warnings_of(_write(tmp_path, text)) == []
    text = _edit("Rx = 0.05", "Rx = 300") + "[checks]\nplausibility = false\n"
    assert _warnings_of(_write(tmp_path, text)) == []


def test_a_load_in_kn_on_a_railway_wheel_is_warned_about(tmp_path):
    """rail_traction with P = 100 (kN typed as N) on its 10 t body: P = 1.0e-3 M g."""
    text = (SCENARIOS / "rail_traction.toml").read_text()
    text = _edit("P = 100.0e3", "P = 100.0", text)
    text = text[: text.index("[[reference]]")]
    msgs = _warnings_of(_write(tmp_path, text))
    ratio = 100.0 / (1.0e4 * G)
    assert any(f"inputs.P = 100.0: the largest load is {ratio:.3g} times the weight" in m
               for m in msgs), msgs  # fmt: skip
    assert _warnings_of(_write(tmp_path, text + '[checks]\naccept = ["P"]\n')) == []


def test_a_load_below_one_newton_is_warned_about(tmp_path):
    text = _edit("P = 1000.0", "P = 0.5", (SCENARIOS / "sweep.toml").read_text())
    msgs = _warnings_of(_write(tmp_path, text))
    assert any("inputs.P = 0.5: the largest load of the run is below 1 N" in m for m in msgs)


def test_a_compliance_in_m_per_mpa_is_warned_about_with_the_contact_size(tmp_path):
    """k1 = k2 = 5e-7 (m/MPa typed as m/Pa): Eq. (34) gives a1 = 0.082 m > Rx = 0.05 m."""
    text = _edit("k1 = 5.0e-13", "k1 = 5.0e-7", _edit("k2 = 5.0e-13", "k2 = 5.0e-7"))
    msgs = _warnings_of(_write(tmp_path, text))
    assert any("parameters.k1 = 5e-07: a layer compliance over 1e-08 m/Pa" in m for m in msgs)
    semi = [m for m in msgs if "contact semi-axis a1" in m]
    # delta = sqrt(P (k1 + k2)/pi) (Rx Ry)^(-1/4) = 0.06709 m, a1 = sqrt(2 Rx delta) = 0.0819 m
    assert len(semi) == 1 and "a1 (m) = 0.0819: 1.6 Rx" in semi[0], semi
    quiet = text + '[checks]\naccept = ["k1", "k2", "semi_axes"]\n'
    assert _warnings_of(_write(tmp_path, quiet)) == []


@pytest.mark.parametrize(
    ("old", "new", "fragment"),
    [
        ("Ry = inf, E = 210.0e9", "Ry = inf, E = 210000.0",
         "halfspace.body.E = 210000.0: a Young's modulus below 1e+06 Pa"),
        ("Ry = 0.30, E", "Ry = 300.0, E", "halfspace.substrate.Ry = 300.0: a radius over 10 m"),
    ],
)  # fmt: skip
def test_halfspace_moduli_in_mpa_and_radii_in_mm_are_warned_about(tmp_path, old, new, fragment):
    text = _edit(old, new, (SCENARIOS / "rail_creep.toml").read_text())
    msgs = _warnings_of(_write(tmp_path, text))
    assert any(fragment in m for m in msgs), msgs


def test_accept_names_only_checked_keys(tmp_path):
    msg = _refused(_write(tmp_path, SCENE + '[checks]\naccept = ["Rz"]\n'))
    assert "checks.accept = ['Rz'] is invalid: must be a list of checked keys: 'Rz' is none" in msg
    msg = _refused(_write(tmp_path, SCENE + '[checks]\nplausibility = "no"\n'))
    assert "checks.plausibility = 'no' is invalid: must be true or false" in msg


def test_the_cli_prints_a_warning_once(tmp_path, capsys):
    path = _write(tmp_path, _edit("Rx = 0.05", "Rx = 300") + '[[cases]]\nname = "a"\n'
                  '[[cases]]\nname = "b"\n')  # fmt: skip
    cli._load_warning_once(path)
    err = capsys.readouterr().err
    assert err.count("parameters.Rx = 300") == 1 and err.startswith("warning: "), err


# ---- the command line -----------------------------------------------------------------------
def test_cli_error_names_the_file_once_on_one_line(tmp_path, capsys):
    path = _write(tmp_path, _edit("mu = 0.3", 'mu = "0.9"'))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    line = err.splitlines()[0]
    assert line.count(str(path)) == 1 and "parameters.mu = '0.9'" in line, err


def test_cli_run_without_references_says_nothing_was_compared(tmp_path, capsys):
    """Not PASS: a scene without references compares nothing; the exit code is 0 and the
    plot's caption does not mention circles that are not drawn."""
    path = _write(tmp_path, SCENE)
    out = tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out)]) == 0
    stdout = capsys.readouterr().out
    assert "no references: nothing compared" in stdout and "PASS" not in stdout
    caption = Image.open(out / "scenes/mini/mini.png").text["Description"]
    assert caption == "lines: FMU via fmpy"


# ---- axis labels ----------------------------------------------------------------------------
def test_axis_labels_carry_units():
    assert axis_label("Tx") == "Tx (N)" and axis_label("time") == "time (s)"
    assert axis_label("xi_x") == "xi_x (-)" and axis_label("Mz") == "Mz (N m)"
    assert axis_label("My_ex.sine.amplitude") == "My_ex.sine.amplitude (N m)"
    assert axis_label("My_ex.sine.period") == "My_ex.sine.period (s)"
    assert axis_labels(["Tx", "Ty"]) == "Tx, Ty (N)"
    assert axis_labels(["Tx", "Mz"]) == "Tx (N), Mz (N m)"
    # max |Tx|/(mu P): N/N, dimensionless; Mz/P: N m / N = m
    assert metric_label(Metric("peak", "Tx", "max_abs", ("mu", "P"))).endswith("(-)")
    assert metric_label(Metric("arm", "Mz", "max", ("P",))).endswith("(m)")
    assert metric_label(Metric("t", "vx", "settle_time", tol=1e-3)).endswith("(s)")


def test_every_shipped_scene_plot_axis_has_a_unit():
    """Unscaled axes get the variable's unit; a scene's own scale label is a ratio
    ("Tx / (mu P)") or names its unit ("t (ms)")."""
    for path in discover(SCENARIOS):
        scene = load(path)
        labels = [scene_plot._panel_label(scene, p) for p in scene.plot.panels]
        labels.append(scene_plot._scaled(scene, scene.plot.x, 1.0)[1])
        for label in labels:
            assert "(" in label or " / " in label, (scene.name, label)


def test_sweep_plot_axes_carry_units(tmp_path, monkeypatch):
    """The study's heat map: varied names with their units, the metric with its own
    (max |Tx|/(mu P): dimensionless)."""
    import matplotlib.axes

    from contact_fmu.study.plot import plot as study_plot

    seen: list[str] = []
    for name in ("set_xlabel", "set_ylabel"):
        orig = getattr(matplotlib.axes.Axes, name)
        monkeypatch.setattr(
            matplotlib.axes.Axes, name,
            lambda self, label, *a, _o=orig, **k: (seen.append(label), _o(self, label, *a, **k))[1],
        )  # fmt: skip
    rows = [{"Iy": iy, "My_ex.sine.amplitude": a, "case": "c", "peak": iy + a}
            for iy in (1e-4, 5e-4) for a in (0.0, 1.0)]  # fmt: skip
    metric = Metric("peak", "Tx", "max_abs", ("mu", "P"))
    varied = ["Iy", "My_ex.sine.amplitude"]
    study_plot(rows, varied, "peak", "Iy", None, tmp_path / "a.png", metrics=[metric])
    study_plot(rows, varied, "peak", "Iy", "My_ex.sine.amplitude", tmp_path / "b.png")
    assert "Iy (kg m^2)" in seen and "My_ex.sine.amplitude (N m)" in seen
    assert "peak: max_abs of Tx/(mu P) (-)" in seen


def test_a_study_varies_an_integer_parameter_with_its_float_values():
    """Study values are floats ("32:64:3"); a whole one is the integer the schema asks for."""
    from contact_fmu.scenario import variation

    scene = load(SCENARIOS / "fig12_transient.toml")
    varied = variation.apply(scene, {"nx": 48.0})
    assert all(c.parameters["nx"] == 48 and type(c.parameters["nx"]) is int for c in varied.cases)
    with pytest.raises(ScenarioError, match=r"parameters.nx = 48.5 is invalid: must be an integer"):
        variation.apply(scene, {"nx": 48.5})
