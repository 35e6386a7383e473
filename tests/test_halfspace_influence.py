"""Influence coefficients of rectangular elements and their FFT convolution.

The closed-form rectangle integrals are checked against scipy quadrature of the
point-load kernels of Love/Johnson (Cerruti: Johnson Eq. 3.86; Boussinesq: Eq. 3.19),
written out here independently; the FFT convolution against the direct sum.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from contact_fmu.halfspace.influence import (
    Grid,
    boussinesq_kernel,
    cerruti_kernels,
    coupling_kernels,
    plane_strain_kernel,
    tangential_operator,
)

G, NU = 80e9, 0.3
DX, DY = 1.0e-4, 0.7e-4


def _cell_quad(f, X, Y, scale):
    """int over the source element centred at the origin of f(X - x', Y - y'); ``scale``
    sets the absolute tolerance (1e-10 of it, below the 1e-8 of the assertions) for
    integrals that vanish by symmetry."""
    return integrate.dblquad(
        lambda yp, xp: f(X - xp, Y - yp),
        -DX / 2,
        DX / 2,
        -DY / 2,
        DY / 2,
        epsabs=1e-10 * scale,
        epsrel=1e-10,
    )[0]


@pytest.mark.parametrize("ox, oy", [(1, 0), (0, 2), (1, 1), (3, -2), (-5, 4)])
def test_rectangle_integrals_match_quadrature_of_point_loads(ox, oy):
    """Cerruti u_x = 1/(pi G)[(1-nu)/r + nu x^2/r^3] tau_x + nu x y/r^3 tau_y (two bodies),
    Boussinesq w = 1/(pi E*) p/r and the coupling x/r^2, integrated over an element away
    from the field point: the closed forms agree with quadrature to its accuracy."""
    X, Y = ox * DX, oy * DY
    Xa, Ya = np.array(X), np.array(Y)
    axx, ayy, axy = (float(v) for v in cerruti_kernels(Xa, Ya, DX, DY, G, NU))
    c = 1.0 / (math.pi * G)

    def kxx(x, y):
        r = math.hypot(x, y)
        return c * ((1 - NU) / r + NU * x * x / r**3)

    def kyy(x, y):
        r = math.hypot(x, y)
        return c * ((1 - NU) / r + NU * y * y / r**3)

    def kxy(x, y):
        return c * NU * x * y / math.hypot(x, y) ** 3

    # quadrature relative accuracy 1e-10; the closed forms are exact up to round-off
    s = abs(axx)
    assert axx == pytest.approx(_cell_quad(kxx, X, Y, s), rel=1e-8)
    assert ayy == pytest.approx(_cell_quad(kyy, X, Y, s), rel=1e-8)
    assert axy == pytest.approx(_cell_quad(kxy, X, Y, s), rel=1e-8, abs=1e-8 * s)
    Estar = 2.3e11
    w = float(boussinesq_kernel(Xa, Ya, DX, DY, Estar))
    ref_w = _cell_quad(lambda x, y: 1 / (math.pi * Estar * math.hypot(x, y)), X, Y, w)
    assert w == pytest.approx(ref_w, rel=1e-8)
    kappa = 0.1
    cx, cy = (float(v) for v in coupling_kernels(Xa, Ya, DX, DY, G, kappa))
    sc = abs(cx) + abs(cy)
    qx = _cell_quad(lambda x, y: -kappa / (math.pi * G) * x / (x * x + y * y), X, Y, sc)
    qy = _cell_quad(lambda x, y: -kappa / (math.pi * G) * y / (x * x + y * y), X, Y, sc)
    assert cx == pytest.approx(qx, rel=1e-8, abs=1e-8 * sc)
    assert cy == pytest.approx(qy, rel=1e-8, abs=1e-8 * sc)


def test_self_influence_of_a_rectangle():
    """The singular self term: int 1/r over a rectangle 2a x 2b about its centre is
    4 (a asinh(b/a) + b asinh(a/b)) (Love 1929); the x^2/r^3 and y^2/r^3 parts split
    it into 4 b asinh(a/b) and 4 a asinh(b/a)."""
    a, b = DX / 2, DY / 2
    z = np.array(0.0)
    axx, ayy, axy = (float(v) for v in cerruti_kernels(z, z, DX, DY, G, NU))
    i1 = 4 * (a * math.asinh(b / a) + b * math.asinh(a / b))
    i_xx = 4 * b * math.asinh(a / b)
    c = 1 / (math.pi * G)
    assert axx == pytest.approx(c * ((1 - NU) * i1 + NU * i_xx), rel=1e-13)
    assert ayy == pytest.approx(c * ((1 - NU) * i1 + NU * (i1 - i_xx)), rel=1e-13)
    assert axy == 0.0


def test_plane_strain_kernel_is_the_log_potential():
    """2-D: u = -(2(1-nu)/(pi G)) int ln(|x|/L) dx' over an element (quadrature)."""
    L = 1.0
    for o in (0.0, 1.0, 3.0):
        X = o * DX
        v = float(plane_strain_kernel(np.array(X), DX, G, NU, L))
        ref = integrate.quad(
            lambda xp, X=X: -(2 * (1 - NU) / (math.pi * G)) * math.log(abs(X - xp) / L),
            -DX / 2,
            DX / 2,
            points=[X] if abs(X) < DX / 2 else None,
            epsrel=1e-12,
        )[0]
        assert v == pytest.approx(ref, rel=1e-9)


def test_fft_convolution_equals_the_direct_sum():
    """u_I = sum_J A(I - J) q_J: the zero-padded FFT convolution equals the dense sum
    (round-off only, 1e-12 of the largest displacement)."""
    g = Grid(9, 6, DX, DY, 0.0, 0.0)
    op = tangential_operator(g, G, NU, k=1e-13)
    rng = np.random.default_rng(3)
    q = rng.standard_normal((2, 6, 9)) * 1e6
    u = op.apply(q)
    mask = np.ones(g.shape, bool)
    M = op.dense(mask)
    ref = M @ np.concatenate([q[0].ravel(), q[1].ravel()])
    scale = np.abs(ref).max()
    assert np.abs(u[0].ravel() - ref[:54]).max() < 1e-12 * scale
    assert np.abs(u[1].ravel() - ref[54:]).max() < 1e-12 * scale


@pytest.mark.parametrize("nu, aspect", [(0.0, 1.0), (0.5, 1.0), (0.5, 4.0), (0.25, 0.25)])
def test_circulant_symbol_is_positive_definite(nu, aspect):
    """The minimum-image embedding keeps the 2 x 2 symbol positive definite, which the
    deconvolution preconditioner needs (zero padding is indefinite for nu = 0.5)."""
    g = Grid(48, 48, 1.0, aspect, 0.0, 0.0)
    S = np.moveaxis(tangential_operator(g, 1.0, nu).symbols, (0, 1), (-2, -1))
    assert np.linalg.eigvalsh(S).min() > 0.0


def test_scaled_reference_kernels_equal_direct_evaluation():
    """tangential_operator takes its kernel blocks from a reference operator of unit
    element length and modulus scaled by dx/G (the Cerruti coefficients are homogeneous
    of degree 1 in length and -1 in G): they equal the directly evaluated kernel to
    1e-12 of its largest entry (the aspect ratio is a cache key to 12 digits; measured
    2e-13 and below), and a grid of the same shape, aspect ratio and nu at
    another size reuses the reference (the cache holds one entry for both)."""
    from contact_fmu.halfspace.influence import (
        BlockConvolution,
        Grid,
        _cerruti_reference,
        cerruti_kernels,
        tangential_operator,
    )

    _cerruti_reference.cache_clear()
    for scale in (1.0, 0.37):
        g = Grid(13, 9, 2e-4 * scale, 3e-4 * scale, -1e-3, -1e-3)
        G, nu = 81e9, 0.28
        op = tangential_operator(g, G, nu)

        def kern(X, Y, g=g, G=G, nu=nu):
            axx, ayy, axy = cerruti_kernels(X, Y, g.dx, g.dy, G, nu)
            return ((axx, axy), (axy, ayy))

        ref = BlockConvolution(g, kern)
        assert np.abs(op.torus - ref.torus).max() <= 1e-12 * np.abs(ref.torus).max()
        assert np.abs(op.symbols - ref.symbols).max() <= 1e-12 * np.abs(ref.symbols).max()
    assert _cerruti_reference.cache_info().currsize == 1
