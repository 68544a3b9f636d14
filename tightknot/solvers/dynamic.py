"""Implicit-Euler dynamics as a minimisation, sharing the Newton loop of the static solver.

Each step minimises ``Phi(q) = Pi(q) + sum m/(2 dt^2) |q - q_hat|^2`` with the prediction
``q_hat = q_n + dt v_n``; its stationarity is implicit Euler,
``M (q - q_n - dt v_n)/dt^2 = -grad Pi(q)``, and ``v_{n+1} = (q_{n+1} - q_n)/dt``
(backward Euler dissipates energy, so a free swinging rod's energy never grows; Hairer &
Wanner 1996, sec. IV.3). Without inertia (dt -> infinity) the step is the static solve.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from tightknot.solvers.newton import NewtonOptions, NewtonResult, newton
from tightknot.solvers.program import Coroutine, program
from tightknot.solvers.system import Inertia, RodSystem


@dataclass
class DynamicStep:
    """Outcome of one implicit-Euler step."""

    time: float
    newton: NewtonResult
    kinetic_energy: float


def kinetic_energy(system: RodSystem) -> float:
    """Kinetic energy of the state [J] (lumped masses, twist inertia)."""
    m = system.model
    st = system.state
    ke = 0.5 * float(np.sum(m.vertex_mass[:, None] * st.v**2))
    if m.twist:
        ke += 0.5 * float(np.sum(m.edge_rot_inertia * st.theta_dot**2))
    return ke


def implicit_euler_step(
    system: RodSystem, dt: float, options: NewtonOptions | None = None
) -> DynamicStep:
    """Advance the system's state by ``dt`` [s] with implicit Euler.

    On a failed Newton solve the state is left unchanged and the result says so. The
    residual tolerance is never below the inertia term's round-off floor
    (:func:`inertia_tolerance`), which short steps raise.
    """
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be finite and > 0 s, got {dt!r}")
    m = system.model
    if not (m.vertex_mass > 0).all():
        raise ValueError("implicit dynamics needs density > 0 for every rod")
    st = system.state
    q_n = system.full_dofs()
    vel = np.zeros(m.dof_count)
    vel[m.position_dofs] = st.v
    if m.twist:
        vel[m.edge_dof] = st.theta_dot
    saved = st.copy()
    system.inertia = Inertia(dt=dt, q_hat=q_n + dt * vel, mass=system.dof_mass)
    opts = inertia_tolerance(system, dt, options or NewtonOptions())
    try:
        res = newton(system, system.free_vector(), opts).run()
    finally:
        system.inertia = None
    if not res.converged:
        system.state = saved
        return DynamicStep(st.time, res, kinetic_energy(system))
    q = system.full_dofs()
    v = (q - q_n) / dt
    st = system.state
    st.v = v[m.position_dofs]
    if m.twist:
        st.theta_dot = v[m.edge_dof]
    st.time = saved.time + dt
    return DynamicStep(st.time, res, kinetic_energy(system))


def inertia_tolerance(system: RodSystem, dt: float, options: NewtonOptions) -> NewtonOptions:
    """``options`` with the residual tolerance raised to the round-off floor of the inertia
    term where a short time step puts it above the requested one.

    The inertia force ``m/dt^2 (q - q_hat)`` is computed from absolute coordinates, each
    known to eps |q|, so it carries a round-off of ``m/dt^2 eps |q|``; in the residual's
    units (forces over EI/L^2) that is a floor no Newton iterate can go below. Four times
    the estimate is asked; above 1e-5 s the floor is below 1e-8 for the study's rod and
    nothing changes (docs/design_notes.md, implicit dynamics).
    """
    free = system.pattern.free_dofs
    if free.size == 0:
        return options
    w = system.dof_mass[free] / dt**2
    q = np.abs(system.full_dofs()[free])
    scale = np.where(system.free_is_theta, system.moment_scale, system.force_scale)
    floor = 4.0 * np.finfo(np.float64).eps * float(np.max(w * np.maximum(q, 1.0e-300) / scale))
    if floor <= options.residual_tol:
        return options
    return dataclasses.replace(options, residual_tol=floor)


@dataclass
class ProximalResult:
    """Outcome of a proximal (fully damped implicit) relaxation."""

    converged: bool
    steps: int
    newton_iterations: int
    reason: str


@program
def proximal(p: RodSystem, dt: float = 1e-3, max_steps: int = 200,
             options: NewtonOptions | None = None, grow_below: int = 8) -> Coroutine:
    """Descend to an equilibrium through an instability by proximal steps.

    Each step minimises ``Pi(q) + sum m/(2 dt^2) |q - q_n|^2`` (implicit Euler with the
    velocity reset to zero: the proximal-point method, Rockafellar 1976; Parikh & Boyd 2014
    sec. 4.1), which always lowers the potential and is well posed where the static Hessian
    is not; dt grows after easy steps and shrinks after failed ones. It stops when a static
    Newton solve from the current state converges. The state's velocities stay zero.
    A program (:mod:`tightknot.solvers.program`); ``.run()`` returns the
    :class:`ProximalResult`.
    """
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be finite and > 0 s, got {dt!r}")
    s = p
    if not (s.model.vertex_mass > 0).all():
        raise ValueError("proximal relaxation needs density > 0 for every rod")
    opts = options or NewtonOptions()
    iters = 0
    for k in range(1, max_steps + 1):
        saved = s.state.copy()
        p.inertia = Inertia(dt=dt, q_hat=s.full_dofs(), mass=s.dof_mass)
        try:
            res = yield from newton(p, s.free_vector(), opts)
        finally:
            p.inertia = None
        iters += res.iterations
        if not res.converged:
            s.state = saved
            dt *= 0.25
            continue
        if res.iterations < grow_below:
            dt *= 2.0
        static = yield from newton(
            p, s.free_vector(), NewtonOptions(residual_tol=opts.residual_tol, max_iterations=15))
        iters += static.iterations
        if static.converged:
            return ProximalResult(True, k, iters, "converged")
    return ProximalResult(False, max_steps, iters, "max_steps")
