"""Units and the physical constants of the two tables, typed from the sources.

Everything inside the truth simulator is SI (m, kg, s, N, Pa, rad). The conversion
factors are written here once; nothing is taken from vtable.
"""

from __future__ import annotations

import math

# --- units -------------------------------------------------------------------------------
INCH = 0.0254  # m (exact)
LBF = 4.4482216152605  # N (exact)
KIP = 1000.0 * LBF  # N
PSI = LBF / INCH**2  # Pa
G = 9.80665  # m/s², standard gravity (the run format's 1 g = 386.09 in/s²)
GPM = 231.0 * INCH**3 / 60.0  # m³/s per US gallon per minute
LB_S2_PER_IN = LBF / INCH  # kg
KIP_IN_S2 = KIP * INCH  # kg·m²
LB_IN = LBF * INCH  # N·m

# --- EERC table: one horizontal actuator of three (Table B.5, standard settings) ----------
B5_KP = 5.14e-5 * INCH / PSI  # ΔP feedback gain k_p: in/psi -> m/Pa
B5_KT = 663.0 * INCH**2  # total horizontal gain k_t: in²/s -> m²/s
B5_KCT = 0.0787 * INCH**3 / PSI  # flow-pressure coefficient k_ct: in³/s/psi -> m³/s/Pa
B5_RC = 0.01  # s, RC of the high-pass on the ΔP feedback (eq B.4)
B5_MASS = 86.3 * LB_S2_PER_IN  # table mass per actuator, 100 kips/(3 g)
B5_BETA = 94000.0 * PSI  # oil bulk modulus β (fitted, app. B.4)
B5_AREA = 25.4 * INCH**2  # piston area A (also Table 2.1)
B5_VOLUME = 317.5 * INCH**3  # oil volume V
EERC_ACTUATORS = 3  # H1, H2, H3 (§2.2, Table 2.1)

# --- EERC platen and foundation ------------------------------------------------------------
EERC_PLATEN_WEIGHT = 100.0 * KIP  # §2.2 "about 100,000 lb"; Table 8.1 bare table mass 100 kips
EERC_PITCH_INERTIA = 1251.0 * KIP_IN_S2  # Table 8.1, about the horizontal actuator line
EERC_FOUNDATION_WEIGHT = 1580.0 * KIP  # §2.2: the reaction mass weighs 1,580,000 lb
EERC_SUPPLY_PRESSURE = 3000.0 * PSI  # §2.2: oil at 3,000 psi
EERC_V_MAX = 25.0 * INCH  # §2.2 / Table 2.2: ±25 in/s horizontal
EERC_STROKE = 5.0 * INCH  # Table 2.2: ±5 in horizontal
EERC_TABLE_TOP = 29.7 * INCH  # table top above the horizontal actuator line (run format, §4.2.1)
EERC_VERTICAL_ARM = 72.0 * INCH  # vertical actuators on a 12 ft square (§2.2)
EERC_STABILIZER_ARM = 102.0 * INCH  # passive stabilizers on a 17 ft square (§2.2)
#: a digital controller on the EERC table: transducer gain ±10 V over the ±5 in stroke (an
#: assumption of this simulator, not in the report)
EERC_DISPLACEMENT_GAIN = 10.0 / (5.0 * INCH)  # V/m
SENSOR_CUTOFF = 100.0  # Hz, analog low-pass before digitizing (§2.3)

# --- Table 8.1 / 9.1: hybrid model of the loaded table -----------------------------------
T81_K_THETA = 2.22e10 * LB_IN  # rocking stiffness k_θ, lb-in/rad
T81_C_THETA = 3.70e8 * LB_IN  # rocking damping c_θ, lb-in-s/rad
T81_COUPLED_HZ = 2.58  # §8.6.3: k_θ, c_θ evaluated at the coupled frequency 2.58 Hz
T91_F_O = 9.6  # Hz, loaded-table open-loop frequency (Tables 7.1, 8.1, 9.1)
T91_XI_O = 0.606  # open-loop damping (Table 8.1 prints "%" but the value is a fraction)
T91_K_O = 29.5  # 1/s, open-loop gain
T81_SPECIMEN = {"weight_kip": 68.0, "height_in": 219.0, "f_hz": 2.87, "xi": 0.01}

# --- §8.6.2: the vertical actuators' share of the rocking impedance at 2.58 Hz -------------
S862_K_V = 7.72e9 * LB_IN  # lb-in/rad (from Fig. 5.5b at the coupled frequency)
S862_C_V = 1.04e8 * LB_IN  # lb-in-s/rad
S862_F_R = 21.0  # Hz, assumed pitch open-loop frequency (the report's second choice)

# --- LNEC uniaxial table ("lnec-st1d"), SI as given ----------------------------------------
LNEC = {
    "platen_mass": 1975.1,  # kg
    "area": 0.012456,  # m²
    "volume": 0.002659,  # m³, total oil volume
    "beta": 193.7e6,  # Pa, effective bulk modulus
    "valve_tau": 0.0246,  # s, servovalve time constant
    "valve_gain": 1.9345e-3,  # m³/s/V, valve flow gain x amplifier gain
    "disp_gain": 129.93,  # V/m, displacement transducer gain
    "leakage": 1.674e-10,  # m³/s/Pa
    "damping": 5780.0,  # N·s/m
    "stroke": 0.100,  # m
    "v_max": 0.40,  # m/s
    "a_max": 25.0,  # m/s²
    "payload": 5000.0,  # kg
    "band_hz": (0.0, 25.0),
}


def hz(w: float) -> float:
    return w / (2.0 * math.pi)
