MMT K&E model as TPOINT fitted mmt_20210821_k_and_e.dat (values from shared/data/real/README.md)
T  80  0.932  0.0000  0.0000
  IA      +1209.2612     1.28477
  IE         -2.9933     0.30382
  NPAE       -3.4724     1.54670
  CA         -5.9455     1.86697
  AN         +2.4950     0.11892
  AW        -10.3347     0.11843
  TF        +21.4118     0.89062
  TX         -2.7165     0.28183
END
