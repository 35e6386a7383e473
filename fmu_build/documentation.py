"""What an FMU carries about itself: documentation/index.html, the licences, model.png.

As the Modelica Reference-FMUs do, each FMU documents itself: ``index.html`` says what
the model is, its equations in short, every variable of this FMU with unit, start and
range (from ``contact_fmu.fmu.variables``, so it cannot disagree with the model
description), how to use it, and the scene's figure where the repository has one
(docs/figures/scene_<name>.png). The licences are the project's (LICENSE, MIT) and
pythonfmu's, whose binary the FMU carries. ``model.png`` is the icon importers show,
drawn with matplotlib.

``files(cfg, identifier)`` returns the entries (path inside the FMU, bytes); the build
puts them into the archive. ``sources(cfg)`` lists the repository files they are made
from, which are part of the FMU's content key.
"""

from __future__ import annotations

import html
import io
from importlib import metadata
from pathlib import Path

from contact_fmu.fmu import variables as fv
from contact_fmu.fmu.config import ModelConfig

ROOT = Path(__file__).resolve().parents[1]
LICENSE = ROOT / "LICENSE"
FIGURES = ROOT / "docs" / "figures"
ICON_PX = 128  # model.png: square, pixels

_WHAT = {
    "body": (
        "a body rolling or sliding on a substrate: the FMU owns the rigid-body dynamics "
        "(Eqs. 8-11) and the frictional contact law, and integrates the stiff slip "
        "equation inside with an L-stable scheme, so any communication step is stable."
    ),
    "contact": (
        "a force element: given the kinematics (Vx, Omega_y, and Vy, Omega_z where "
        "present) and the normal load P, it returns the frictional forces of the contact "
        "law at once (direct feedthrough, no state). The host owns the dynamics."
    ),
    "rigid_body": (
        "the rigid body of Eqs. (8)-(9) alone, driven by the frictional force Tx of a "
        "contact-mode FMU connected to it in a co-simulation master."
    ),
}

_EQUATIONS = {
    "body": [
        "M dVx/dt = Fx_ex - Tx;  Iy dOmega_y/dt = My_ex + Rx Tx  (Eqs. 8-9)",
        "M dVy/dt = Fy_ex - Ty;  Iz dOmega_z/dt = Mz_ex - Mz  (Eqs. 10-11, where present)",
        "rigid slip at the contact centre: vx = Vx - Omega_y Rx, vy = Vy  (Eq. 3)",
        "creep law: T = mu P h(beta) v/|v|, |T| <= mu P (Coulomb; Eqs. 40-43 for the "
        "thin-layer law, or the tabulated Boussinesq-Cerruti half-space law)",
    ],
    "contact": [
        "rigid slip at the contact centre: vx = Vx - Omega_y Rx, vy = Vy  (Eq. 3)",
        "creep law: T = mu P h(beta) v/|v|, |T| <= mu P (Coulomb; Eqs. 40-43 for the "
        "thin-layer law, or the tabulated Boussinesq-Cerruti half-space law)",
        "contact ellipse a1, a2 and peak pressure p0 from P (Eq. 34)",
    ],
    "rigid_body": [
        "M dVx/dt = Fx_ex - Tx;  Iy dOmega_y/dt = My_ex + Rx Tx  (Eqs. 8-9), exact for "
        "inputs held over the step",
    ],
}

_USE = {
    "body": (
        "Set the parameters before initialisation, then drive the inputs every "
        "communication step; the outputs are states. A communication step h is split "
        "into ceil(h/h_max) internal steps with the inputs held."
    ),
    "contact": (
        "Connect Vx and Omega_y (and Vy, Omega_z where present) from the body's "
        "dynamics and Tx back to it. Exchanged explicitly, the stiff creep force needs "
        "a communication step below the slip relaxation time M A2 |Vx| / (dTx/dxi), "
        "about 1e-5 s for the paper's parameters; `contact-fmu system SCENE` writes such "
        "a coupled system (SSP and OspSystemStructure.xml)."
    ),
    "rigid_body": (
        "Couple with a contact-mode FMU (Vx, Omega_y to it, Tx from it) at a "
        "communication step below the slip relaxation time; `contact-fmu system SCENE` "
        "writes the coupled system."
    ),
}


def scene_figure(cfg: ModelConfig) -> Path | None:
    """The repository's figure of the scene the FMU was built for, if there is one."""
    fig = FIGURES / f"scene_{cfg.name}.png"
    return fig if fig.is_file() else None


def sources(cfg: ModelConfig) -> list[Path]:
    """The repository files the documentation is made of (part of the content key)."""
    return [p for p in (LICENSE, scene_figure(cfg)) if p is not None and p.is_file()]


def _range(cfg: ModelConfig, var: fv.Var) -> str:
    lo, hi = cfg.bounds(var)
    if lo is not None and lo == hi:
        return f"fixed at {lo:g}"
    parts = []
    if lo is not None:
        parts.append(f"{'>' if var.open_min and var.name not in cfg.fixed else '>='} {lo:g}")
    if hi is not None:
        parts.append(f"<= {hi:g}")
    return ", ".join(parts)


def variables_html(cfg: ModelConfig) -> str:
    """The FMU's variables as an HTML table, in value-reference order."""
    rows = [
        "<table>",
        "<tr><th>name</th><th>causality</th><th>variability</th><th>type</th><th>unit</th>"
        "<th>start</th><th>range</th><th>description</th></tr>",
    ]
    for var in cfg.variables:
        causality = var.causality[cfg.mode]
        start = "" if causality == fv.OUTPUT else repr(cfg.start(var))
        cells = (
            var.name,
            causality,
            fv.variability(var, cfg.mode),
            var.type,
            var.unit or "",
            start,
            _range(cfg, var),
            var.description,
        )
        rows.append("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in cells) + "</tr>")
    rows.append("</table>")
    return "\n".join(rows)


# the FMU's binary, per build target: what the host needs, the licences it carries
_TARGETS = {
    "pythonfmu": (
        "The FMU's Python parts run in the importing process: the host needs Python 3.11 "
        "with numpy and scipy (pythonfmu's binary; on Linux it needs glibc 2.32 and GCC "
        "12's libstdc++, GLIBCXX_3.4.30, or newer).",
        '<p>MIT: see <a href="licenses/LICENSE.txt">licenses/LICENSE.txt</a>; pythonfmu '
        '(the FMU\'s inner binary): <a href="licenses/pythonfmu-LICENSE.txt">'
        "licenses/pythonfmu-LICENSE.txt</a>.</p>",
    ),
    "native": (
        "A native C FMU (binaries/linux64 and its C sources under sources/): any FMI 2.0 "
        "importer runs it, with no Python on the host (on Linux: glibc 2.17 or newer, "
        "libm). To build it from sources/ elsewhere, compile every .c file there with the "
        "FMI 2.0 headers into one shared library and link the C math library (-lm where "
        "it is separate); with fmpy: fmpy.build.build_platform_binary(folder, "
        "cmake_options={'CMAKE_C_STANDARD_LIBRARIES:STRING': '-lm'}), as fmpy's cmake "
        "links no library by itself.",
        '<p>MIT: see <a href="licenses/LICENSE.txt">licenses/LICENSE.txt</a>.</p>',
    ),
}


def index_html(
    cfg: ModelConfig, identifier: str, figure: str | None, target: str = "pythonfmu"
) -> str:
    """documentation/index.html of the FMU for ``cfg`` built for ``target`` (pythonfmu or
    native)."""
    host, licence = _TARGETS[target]
    e = html.escape
    title = cfg.description or f"{identifier}: {cfg.mode}-mode contact FMU"
    law = {"layer": "thin compliant layers (Eqs. 31-43)", "halfspace": "elastic half-spaces"}
    eqs = "\n".join(f"<li><code>{e(q)}</code></li>" for q in _EQUATIONS[cfg.mode])
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{e(identifier)}</title>",
        "<style>body{font-family:sans-serif;max-width:60em;margin:auto}"
        "table{border-collapse:collapse}td,th{border:1px solid #999;padding:2px 6px;"
        "vertical-align:top}code{white-space:pre-wrap}</style>",
        "</head><body>",
        f"<h1>{e(identifier)}</h1>",
        f"<p>{e(title)}</p>",
        "<h2>The model</h2>",
        "<p>Rolling/sliding contact of an elastic body on an elastic substrate after "
        "Spector &amp; Batra (1995), <i>On the Motion of an Elastic Body Rolling/Sliding "
        "on an Elastic Substrate</i>, as an FMI 2.0 co-simulation FMU built with "
        f"contact_fmu. This FMU ({e(cfg.mode)} mode) is {e(_WHAT[cfg.mode])}</p>",
    ]
    if cfg.mode != "rigid_body":
        parts.append(f"<p>Contact law: {e(law[cfg.contact_law])}.</p>")
    parts += [
        "<h2>Equations in short</h2>",
        f"<ul>\n{eqs}\n</ul>",
        "<p>SI units throughout. Tx is the force the body exerts on the substrate; the "
        "body receives -Tx.</p>",
        "<h2>Variables</h2>",
        "<p>Ranges are checked by the FMU: a value outside answers fmi2Error at the "
        "setter, and the steps are discarded until it is corrected. A range written "
        "&gt; is strict (FMI's min is inclusive).</p>",
        variables_html(cfg),
        "<h2>How to use it</h2>",
        f"<p>{e(_USE[cfg.mode])}</p>",
        f"<p>{e(host)} With fmpy:</p>",
        "<pre><code>import fmpy\n"
        f"fmpy.dump({identifier + '.fmu'!r})\n"
        f"result = fmpy.simulate_fmu({identifier + '.fmu'!r}, stop_time=..., "
        "output_interval=...)</code></pre>",
    ]
    if figure is not None:
        parts += [
            "<h2>The scene</h2>",
            f'<p><img src="{e(figure)}" alt="the scene {e(cfg.name)} run by fmpy" '
            'style="max-width:100%"></p>',
        ]
    parts += [
        "<h2>Licence</h2>",
        licence,
        "</body></html>",
        "",
    ]
    return "\n".join(parts)


def icon_png() -> bytes:
    """model.png: a wheel on a rail with its contact patch, drawn with matplotlib."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle, Ellipse, Rectangle

    fig = Figure(figsize=(1.0, 1.0), dpi=ICON_PX)
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    ax.set_xlim(-1.0, 1.0)
    ax.set_ylim(-1.0, 1.0)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.add_patch(Rectangle((-1.0, -1.0), 2.0, 0.42, color="#6b7b8c"))
    ax.add_patch(Circle((0.0, 0.12), 0.7, color="#2f5d8a"))
    ax.add_patch(Circle((0.0, 0.12), 0.16, color="white"))
    ax.add_patch(Ellipse((0.0, -0.58), 0.5, 0.12, color="#e07b39"))
    ax.annotate("", xy=(0.85, 0.12), xytext=(0.35, 0.12),
                arrowprops={"arrowstyle": "->", "color": "#e07b39", "lw": 3})  # fmt: skip
    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None})
    return buf.getvalue()


def _pythonfmu_license() -> bytes:
    dist = metadata.distribution("pythonfmu")
    for f in dist.files or ():
        if Path(str(f)).name.upper().startswith("LICENSE"):
            return Path(dist.locate_file(f)).read_bytes()
    return (
        b"pythonfmu is distributed under the MIT licence (https://github.com/NTNU-IHB/PythonFMU).\n"
    )


def files(cfg: ModelConfig, identifier: str, target: str = "pythonfmu") -> dict[str, bytes]:
    """The FMU's documentation entries: path inside the FMU -> content."""
    fig = scene_figure(cfg)
    out = []
    figure_name = None
    if fig is not None:
        figure_name = f"scene_{cfg.name}.png"
        out.append((f"documentation/{figure_name}", fig.read_bytes()))
    out += [
        ("documentation/index.html", index_html(cfg, identifier, figure_name, target).encode()),
        ("documentation/licenses/LICENSE.txt", LICENSE.read_bytes()),
        ("model.png", icon_png()),
    ]
    if target == "pythonfmu":
        out.append(("documentation/licenses/pythonfmu-LICENSE.txt", _pythonfmu_license()))
    return dict(out)
