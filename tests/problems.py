"""Reference problems shared by the solver tests and benchmarks (published definitions)."""

import numpy as np

# --- Robertson's chemical kinetics in DAE form (Hairer & Wanner II, sec. IV.10) ----------
ROBERTSON_Y0 = np.array([1.0, 0.0, 0.0])
ROBERTSON_YP0 = np.array([-0.04, 0.04, 0.0])


def robertson(t, y, yp):
    return np.array(
        [
            yp[0] + 0.04 * y[0] - 1e4 * y[1] * y[2],
            yp[1] - 0.04 * y[0] + 1e4 * y[1] * y[2] + 3e7 * y[1] ** 2,
            y[0] + y[1] + y[2] - 1.0,
        ]
    )


# --- Chemical Akzo Nobel (CHEMAKZO), Test Set for IVP Solvers, University of Bari --------
K1, K2, K3, K4, KBIG, KLA, KS, PO2, HEN = 18.7, 0.58, 0.09, 0.42, 34.4, 3.3, 115.83, 0.9, 737.0
AKZO_Y0 = np.array([0.444, 0.00123, 0.0, 0.007, 0.0, KS * 0.444 * 0.007])
AKZO_REF = np.array(
    [
        0.1150794920661702,
        0.1203831471567715e-2,
        0.1611562887407974,
        0.3656156421249283e-3,
        0.1708010885264404e-1,
        0.4873531310307455e-2,
    ]
)


def akzo(t, y, yp):
    sq = np.sqrt(y[1]) if y[1] >= 0.0 else np.nan
    r1 = K1 * y[0] ** 4 * sq
    r2 = K2 * y[2] * y[3]
    r3 = K2 / KBIG * y[0] * y[4]
    r4 = K3 * y[0] * y[3] ** 2
    r5 = K4 * y[5] ** 2 * sq
    fin = KLA * (PO2 / HEN - y[1])
    return np.array(
        [
            yp[0] - (-2.0 * r1 + r2 - r3 - r4),
            yp[1] - (-0.5 * r1 - r4 - 0.5 * r5 + fin),
            yp[2] - (r1 - r2 + r3),
            yp[3] - (-r2 + r3 - 2.0 * r4),
            yp[4] - (r2 - r3 + r5),
            KS * y[0] * y[3] - y[5],
        ]
    )


def significant_digits(y, ref):
    """min over components of -log10(|err_i| / |ref_i|) (the Test Set's 'scd')."""
    err = np.abs(np.asarray(y) - ref) / np.abs(ref)
    return float(np.min(-np.log10(np.maximum(err, 1e-300))))


# --- Van der Pol, mu = 1000, as an implicit ODE (Hairer & Wanner II) ----------------------
VDP_MU = 1000.0
VDP_Y0 = np.array([2.0, 0.0])


def vdp_rhs(t, y):
    return np.array([y[1], VDP_MU * (1.0 - y[0] ** 2) * y[1] - y[0]])


# --- HIRES (Test Set for IVP Solvers) -----------------------------------------------------
HIRES_Y0 = np.array([1.0, 0, 0, 0, 0, 0, 0, 0.0057])
HIRES_T_END = 321.8122
HIRES_REF = np.array(
    [
        0.7371312573325668e-3,
        0.1442485726316185e-3,
        0.5888729740967575e-4,
        0.1175651343283149e-2,
        0.2386356198831331e-2,
        0.6238968252742796e-2,
        0.2849998395185769e-2,
        0.2850001604814231e-2,
    ]
)


def hires_rhs(t, y):
    f = np.empty(8)
    f[0] = -1.71 * y[0] + 0.43 * y[1] + 8.32 * y[2] + 0.0007
    f[1] = 1.71 * y[0] - 8.75 * y[1]
    f[2] = -10.03 * y[2] + 0.43 * y[3] + 0.035 * y[4]
    f[3] = 8.32 * y[1] + 1.71 * y[2] - 1.12 * y[3]
    f[4] = -1.745 * y[4] + 0.43 * y[5] + 0.43 * y[6]
    f[5] = -280.0 * y[5] * y[7] + 0.69 * y[3] + 1.71 * y[4] - 0.43 * y[5] + 0.69 * y[6]
    f[6] = 280.0 * y[5] * y[7] - 1.81 * y[6]
    f[7] = -f[6]
    return f


def as_residual(rhs):
    """F(t, y, y') = y' - f(t, y) for an explicit ODE."""

    def residual(t, y, yp):
        return yp - rhs(t, y)

    return residual
