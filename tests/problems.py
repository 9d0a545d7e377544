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


# --- Transistor amplifier (TRANSAMP), Test Set for IVP Solvers, University of Bari --------
# Index-1 DAE of dimension 8, M y' = f(t, y) with a singular, non-diagonal M and the input
# U_e(t) = 0.1 sin(200 pi t) [V], t in [0, 0.2] s. Definition, consistent initial values
# and the reference y(0.2) (PSIDE at rtol = atol = 1e-14 on a Cray C90) are those of the
# Test Set's transamp.f (http://www.dm.uniba.it/~testset/, revision 1.3, 2006), as also
# transcribed in R's deTestSet and OdePkg's odepkg_testsuite_impltrans.m.
TA_UB, TA_UF, TA_ALPHA, TA_BETA = 6.0, 0.026, 0.99, 1e-6  # [V], [V], [-], [A]
TA_R0, TA_R = 1000.0, 9000.0  # R0 and R1 ... R9 [Ohm]
TA_C = np.array([1e-6, 2e-6, 3e-6, 4e-6, 5e-6])  # C1 ... C5 [F]
TRANSAMP_T_END = 0.2
TRANSAMP_Y0 = np.array([0.0, 3.0, 3.0, 6.0, 3.0, 3.0, 6.0, 0.0])
TRANSAMP_YP0 = np.array(
    [
        51.338775,
        51.338775,
        -TA_UB / (2.0 * TA_R * TA_C[1]),  # -(Ub / (R2/R1 + 1)) / (R3 C2)
        -24.9757667,
        -24.9757667,
        -TA_UB / (2.0 * TA_R * TA_C[3]),  # -(Ub / (R6/R5 + 1)) / (R7 C4)
        -10.00564453,
        -10.00564453,
    ]
)
TRANSAMP_REF = np.array(
    [
        -0.5562145012262709e-2,
        0.3006522471903042e1,
        0.2849958788608128e1,
        0.2926422536206241e1,
        0.2704617865010554e1,
        0.2761837778393145e1,
        0.4770927631616772e1,
        0.1236995868091548e1,
    ]
)


def transamp(t, y, yp):
    """Kirchhoff's current law at the 8 nodes [A]: F = M y' - f(t, y) (node voltages y [V])."""
    c1, c2, c3, c4, c5 = TA_C
    ue = 0.1 * np.sin(200.0 * np.pi * t)
    fac1 = TA_BETA * (np.exp((y[1] - y[2]) / TA_UF) - 1.0)
    fac2 = TA_BETA * (np.exp((y[4] - y[5]) / TA_UF) - 1.0)
    r = TA_R
    return np.array(
        [
            (y[0] - ue) / TA_R0 + c1 * (yp[0] - yp[1]),
            y[1] / r + (y[1] - TA_UB) / r + (1.0 - TA_ALPHA) * fac1 - c1 * (yp[0] - yp[1]),
            y[2] / r - fac1 + c2 * yp[2],
            (y[3] - TA_UB) / r + TA_ALPHA * fac1 + c3 * (yp[3] - yp[4]),
            y[4] / r + (y[4] - TA_UB) / r + (1.0 - TA_ALPHA) * fac2 - c3 * (yp[3] - yp[4]),
            y[5] / r - fac2 + c4 * yp[5],
            (y[6] - TA_UB) / r + TA_ALPHA * fac2 + c5 * (yp[6] - yp[7]),
            y[7] / r - c5 * (yp[6] - yp[7]),
        ]
    )


# --- Robertson to t = 1e11: the Test Set's ROBER reference -------------------------------
# y(1e11) from the Test Set for IVP Solvers (rober.f, solut: RADAU5 at rtol = atol = 1e-20
# on a Cray C90; http://www.dm.uniba.it/~testset/), as also used by ODE.jl's tests
ROBERTSON_1E11_REF = np.array([0.2083340149701255e-07, 0.8333360770334713e-13, 0.9999999791665050])

# --- POLLU, air pollution model of the Dutch National Institute of Public Health ---------
# (Verwer 1994), Test Set for IVP Solvers, pollu.f (revision 1.2, 2006): 20 species, 25
# reactions, t in [0, 60]; POLLU_REF is its solut (RADAU5 at rtol = atol = 1.1e-18 on a
# Cray C90). Indices below are the Fortran ones minus 1.
POLLU_K = np.array(
    [.35, .266e2, .123e5, .86e-3, .82e-3, .15e5, .13e-3, .24e5, .165e5, .9e4, .22e-1,
     .12e5, .188e1, .163e5, .48e7, .35e-3, .175e-1, .1e9, .444e12, .124e4, .21e1, .578e1,
     .474e-1, .178e4, .312e1]
)  # fmt: skip
POLLU_Y0 = np.zeros(20)
POLLU_Y0[[1, 3, 6, 7, 8, 16]] = [0.2, 0.04, 0.1, 0.3, 0.01, 0.007]
POLLU_T_END = 60.0
POLLU_REF = np.array(
    [0.5646255480022769e-01, 0.1342484130422339e+00, 0.4139734331099427e-08,
     0.5523140207484359e-02, 0.2018977262302196e-06, 0.1464541863493966e-06,
     0.7784249118997964e-01, 0.3245075353396018e+00, 0.7494013383880406e-02,
     0.1622293157301561e-07, 0.1135863833257075e-07, 0.2230505975721359e-02,
     0.2087162882798630e-03, 0.1396921016840158e-04, 0.8964884856898295e-02,
     0.4352846369330103e-17, 0.6899219696263405e-02, 0.1007803037365946e-03,
     0.1772146513969984e-05, 0.5682943292316392e-04]
)  # fmt: skip


def pollu_rhs(t, y):
    k = POLLU_K
    r = np.empty(25)
    r[0] = k[0] * y[0]
    r[1] = k[1] * y[1] * y[3]
    r[2] = k[2] * y[4] * y[1]
    r[3] = k[3] * y[6]
    r[4] = k[4] * y[6]
    r[5] = k[5] * y[6] * y[5]
    r[6] = k[6] * y[8]
    r[7] = k[7] * y[8] * y[5]
    r[8] = k[8] * y[10] * y[1]
    r[9] = k[9] * y[10] * y[0]
    r[10] = k[10] * y[12]
    r[11] = k[11] * y[9] * y[1]
    r[12] = k[12] * y[13]
    r[13] = k[13] * y[0] * y[5]
    r[14] = k[14] * y[2]
    r[15] = k[15] * y[3]
    r[16] = k[16] * y[3]
    r[17] = k[17] * y[15]
    r[18] = k[18] * y[15]
    r[19] = k[19] * y[16] * y[5]
    r[20] = k[20] * y[18]
    r[21] = k[21] * y[18]
    r[22] = k[22] * y[0] * y[3]
    r[23] = k[23] * y[18] * y[0]
    r[24] = k[24] * y[19]
    f = np.empty(20)
    f[0] = -r[0] - r[9] - r[13] - r[22] - r[23] + r[1] + r[2] + r[8] + r[10] + r[11] + r[21] + r[24]
    f[1] = -r[1] - r[2] - r[8] - r[11] + r[0] + r[20]
    f[2] = -r[14] + r[0] + r[16] + r[18] + r[21]
    f[3] = -r[1] - r[15] - r[16] - r[22] + r[14]
    f[4] = -r[2] + r[3] + r[3] + r[5] + r[6] + r[12] + r[19]
    f[5] = -r[5] - r[7] - r[13] - r[19] + r[2] + r[17] + r[17]
    f[6] = -r[3] - r[4] - r[5] + r[12]
    f[7] = r[3] + r[4] + r[5] + r[6]
    f[8] = -r[6] - r[7]
    f[9] = -r[11] + r[6] + r[8]
    f[10] = -r[8] - r[9] + r[7] + r[10]
    f[11] = r[8]
    f[12] = -r[10] + r[9]
    f[13] = -r[12] + r[11]
    f[14] = r[13]
    f[15] = -r[17] - r[18] + r[15]
    f[16] = -r[19]
    f[17] = r[19]
    f[18] = -r[20] - r[21] - r[23] + r[22] + r[24]
    f[19] = -r[24] + r[23]
    return f
