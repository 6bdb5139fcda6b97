"""The simulated world: everything that is true in a simulation, and the antenna the
control program drives.

* :mod:`.world`: :class:`~.world.World` assembles a scenario's parts in one simpy
  environment; :class:`~.world.SimulatedAntenna` implements :mod:`controller.protocol` on
  them (the controller sees only what the protocol returns);
* the parts: :mod:`.sky` (true, refracted source positions), :mod:`.weather`, :mod:`.mount`
  (slews, settling, limits, cable wrap), :mod:`.effects` (the catalogue of physical effects
  behind one interface), :mod:`.beam`, :mod:`.receiver`, :mod:`.atmosphere`, :mod:`.camera`.

May import: :mod:`controller` (the protocol it implements, astronomy, and the pointing terms
that express the truth in the controller's vocabulary), :mod:`antsim.tomlcheck`,
:mod:`antsim.schema.keys` (the effects declare their parameters with it) and
:mod:`antsim.scenario` (the type the world is built from); never the run, figures, plans,
diagnosis or the command line. The parts' settings are defined beside them, declared key by
key in :mod:`antsim.schema.scenario` and read by :mod:`antsim.scenario`.
"""
