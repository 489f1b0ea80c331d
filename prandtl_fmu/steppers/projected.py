"""``projected``: the scheme of Bastien & Schatzman (M2AN 2002, eq. 5.1).

    U^{p+1} = proj_K( U^p + h f(t_p, U^p) ),   U = (x, v, u_1..u_n),
    K = R x R x [-eta_1, eta_1] x ... x [-eta_n, eta_n]

that is, with every force taken at the *old* state and the load at t_p:

    a     = ( F(t_p) - k0 x - k3 x^3 - c v - sum_i k_i u_i ) / m
    u_i  <- clip(u_i + h v, -eta_i, eta_i)
    x    <- x + h v
    v    <- v + h a

The papers call this "the implicit Euler scheme" because it is implicit in the
multivalued term d psi_K only (the projection); it is explicit in everything
else. (Our ``implicit`` stepper is implicit in every term.)

Order 1, with a constant uniform in the number of branches n in the max norm
(Bastien & Schatzman, Prop. 6.3 and eq. 7.20). Stability: explicit Euler on
the smooth part, so not stable for any h: in the elastic regime it multiplies
the oscillator's energy by about 1 + (omega h)^2 per step (omega^2 = tangent
stiffness / m) and grows without bound unless friction dissipates faster; it
is unusable once omega h is of order 1.
"""
from .._jit import kernel
from ..kernels.play import shift
from ..kernels.smooth import smooth_force
from ..loads import force_at

ORDER = 1


@kernel
def step(model, load, t, h, x, v, s, u):
    m, k0, k3, c, k, eta = model
    a = (force_at(load, t) - smooth_force(x, v, k0, k3, c) - s) / m
    s = shift(k, eta, u, h * v)
    return x + h * v, v + h * a, s
