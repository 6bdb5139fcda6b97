Hand-made model: fixed (=) and parallel (&) terms, an 8-character harmonic name
T  44  5.460  0.0000  0.0000
  IA       -269.5000     2.56800
 =IE         +0.0000
& HACA2     -11.8900     1.98200
& HSCA5CE8+1234.5678     2.00100
  NPAE      -50.9700     3.61400
 =CA         +0.0000
  AN        +44.2600     1.13000
  AW        +69.8900     1.42800
  TF       +491.2700   131.17900
END
