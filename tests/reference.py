"""Numbers printed in report UCB/EERC-91/13, used as test targets (not as parameters)."""

# Table 6.1: gain margin, phase margin (deg)
TABLE_6_1 = {
    "standard": (3.01, 70.1),
    "delta_p=0": (3.26, 75.4),
    "delta_p=5": (2.53, 59.3),
    "gain=8": (4.61, 76.1),
    "gain=10": (2.56, 64.4),
    "added_mass": (2.80, 56.8),
}

# Table 7.2: gain margin, phase margin (deg)
TABLE_7_2 = {
    "standard": (2.54, 34.5),
    "k_o=25": (2.99, 37.3),
    "k_o=35": (2.14, 34.6),
    "f_o=6": (1.63, 19.8),
    "f_o=15": (3.94, 47.7),
    "xi_o=0.406": (1.71, 39.4),
    "xi_o=0.806": (3.40, 31.9),
    "f_s=2.50": (2.54, 37.7),
    "f_s=2.90": (2.55, 34.1),
    "xi_s=0.004": (2.49, 21.8),
    "xi_s=0.060": (2.61, 43.6),
    "xi_s=0.100": (2.69, 53.6),
    "u=0": (2.48, 50.3),
    "u=0.10": (2.48, 52.2),
    "u=2.00": (2.71, 22.3),
}

# Table 9.2: coupled modes of the Table 9.1 hybrid model
TABLE_9_2_MODES = [(2.5391, 0.040079), (8.1906, 0.259045)]
TABLE_9_2_REAL_ROOTS = [-199.616612, -99.309331, -46.343754]
