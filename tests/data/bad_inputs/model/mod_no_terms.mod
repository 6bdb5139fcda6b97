bad_inputs_base seed 3: fit A
! W1..W10: Ghigo 1990 (NRAO EDIR 288) section II
T  12  11.702  0.0000  0.0000
END
