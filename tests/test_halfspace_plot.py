"""RollingSolution.plot: the traction drawn with the adhesion and slip areas marked."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from contact_fmu.halfspace.railway import wheel_on_rail  # noqa: E402


@pytest.mark.parametrize("vx_sign", [1.0, -1.0])
def test_plot_marks_adhesion_and_slip_and_draws_one_arrow_per_element(tmp_path, vx_sign):
    """Partial slip with spin (Carter's picture: adhesion at the leading edge, slip at
    the trailing edge), rolling forwards and backwards (the mirrored solution): one
    arrow per contact element carrying tau in MPa, the adhesion dots and slip crosses at
    exactly the solution's elements (in mm), the forces in the title, a PNG written."""
    c = wheel_on_rail(n=16)
    xref = c.mu * c.P / (c.elastic.G * c.c**2)
    s = c.traction(vx_sign * 0.3 * xref, 0.1 * xref, 0.2 * xref / c.c, vx_sign)
    assert s.adhesion.any() and s.slip.any()
    ax = s.plot()
    (q,) = [x for x in ax.collections if hasattr(x, "U")]  # the quiver
    C = s.contact
    assert q.N == int(C.sum())
    np.testing.assert_allclose(q.U, s.tau[0][C] * 1e-6, rtol=1e-12)
    X, Y = s.grid.mesh()
    lines = {ln.get_label().split(" ")[0]: ln for ln in ax.get_lines()}
    np.testing.assert_allclose(lines["adhesion"].get_xdata(), X[s.adhesion] * 1e3, rtol=1e-12)
    np.testing.assert_allclose(lines["slip"].get_ydata(), Y[s.slip] * 1e3, rtol=1e-12)
    assert f"{s.Tx:.4g}" in ax.get_title()
    out = tmp_path / "traction.png"
    ax.figure.savefig(out)
    assert out.stat().st_size > 10_000
    plt.close(ax.figure)
