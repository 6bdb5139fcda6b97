"""`antsim serve`: the simulated antenna of a scenario as a KATCP device (docs/katcp.md).

* :mod:`.device`: the KATCP device (aiokatcp): a world driven by requests, one controlling
  client, sensors (:mod:`.sensors`), request arguments parsed with errors naming them
  (:mod:`.arguments`), the program-track table the antenna interpolates
  (:mod:`.programtrack`), and how simulated time passes (:mod:`.clock`);
* :mod:`.app`: serving until stopped (progress lines, signals, ``truth.json`` and the
  request log); :mod:`.process`: a server in a child process, as a test starts one;
* :mod:`.remote`: the project's controller connected to a served antenna
  (``antsim run --connect``), through :mod:`controller.wire`.

May import: :mod:`antsim.world`, :mod:`antsim.scenario`, :mod:`antsim.tomlcheck` and
:mod:`controller`; never the run, figures, studies, plans, diagnosis or the command line,
and nothing but the command line imports it.
"""
