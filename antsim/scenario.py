"""Scenarios: TOML files describing a complete, runnable situation, loaded and validated.

A scenario names the telescope and its site, the campaign window, the sources, the injected
truth (a pointing model plus a list of physical effects), the receiver, beam, atmosphere and
weather, and the control program's own settings (the pointing model in use, the scan, the
scheduler). Every key is declared once, with its kind, unit, range, default and meaning, in
:mod:`antsim.schema.scenario` (``docs/scenarios.md`` is generated from it), and read here
through that declaration: every bad value becomes one :class:`~controller.errors.InputError`
line naming the file, the key and the value; unknown keys are errors too. The checks between
keys (a step within the beam, a band below twice its frequency) are made here, after each
table's keys are read. See ``scenarios/ghigo1990.toml``.

Beyond the 45-ft (``docs/telescopes.md``): ``mount.kind = "equatorial"`` (axes hour angle and
declination; models in TPOINT's equatorial terms, e.g. ``crane11``), ``beam.gain_harmonics``,
``[camera]`` and ``[stars]`` for optical pointing (``controller.method = "optical"``), and
``controller.feed_angles_deg``, ``[controller.tipping]``, ``[controller.gain_curve]``,
``[controller.optical]``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np
from astropy.coordinates import Angle

from controller.astro.site import Site
from controller.errors import InputError
from controller.pointing.crane import REFRACTION_SCALE_TERM
from controller.pointing.equatorial import (
    EQUATORIAL_MODELS,
    equatorial_model,
    equatorial_term,
)
from controller.pointing.model import NAMED_MODELS, PointingModel
from controller.pointing.modelio import load_model
from controller.pointing.terms import TermError, get_term
from controller.pointing.thermal import STRUCTURE_SENSORS, thermal_regressors
from controller.program.campaign import EPHEMERIS_MARGIN_S
from controller.program.config import (
    CatalogSource,
    ControllerConfig,
    OpticalConfig,
    SchedulerConfig,
    SearchConfig,
)
from controller.scans.config import GainCurveConfig, ScanConfig, SkyConfig, TippingConfig

from .schema import scenario as schema
from .schema.keys import Section, duplicate
from .schema.scenario import ESTIMATORS, MAX_SAMPLES, MAX_TIMESCALE_S, UNIT_ARCSEC
from .schema.utc import end_problem, utc_time
from .tomlcheck import Table, load_toml
from .world.atmosphere import AtmosphereConfig
from .world.beam import BeamConfig
from .world.camera import CameraConfig, synthetic_stars
from .world.effects import EFFECTS
from .world.mount import AxisConfig, MountConfig, move_time_s
from .world.receiver import ChannelConfig, ReceiverConfig
from .world.sensors import SensorConfig, thermal_truth
from .world.sky import SourceConfig
from .world.weather import WeatherConfig

__all__ = ["ESTIMATORS", "MAX_SAMPLES", "MAX_TIMESCALE_S", "UNIT_ARCSEC", "EffectSpec",
           "PlanNotScenarioError", "Scenario", "load_scenario"]

#: effects that an equatorial mount accepts: the others model an alt-az mount's geometry,
#: its elevation-dependent structure or its azimuth track
EQUATORIAL_EFFECTS = ("tracking_jitter", "clock_error", "polarization_squint", "beam_width",
                      "source_structure", "refraction_anomaly", "terms", "polar_torsion")
#: effects that model an equatorial mount's structure (refused on an alt-az mount)
EQUATORIAL_ONLY_EFFECTS = ("polar_torsion",)


#: ``[receiver] radiometer_noise = false`` (closure tests): a bandwidth so large that the
#: radiometer noise of a 1-s sample is ~5e-12 K, below anything a test resolves but not zero
#: (a reduction divides by the samples' scatter)
NO_RADIOMETER_BANDWIDTH_MHZ = 1e20
#: the recordings' name of a scan's channels averaged (no receiver channel may take it)
AVERAGE_CHANNEL = "AVG"
#: the smallest step of a five-point scan, in beams (HPBW): the power at +-D is below the
#: peak's by 1 - exp(-4 ln 2 (D / HPBW)^2), 2.8e-4 at a hundredth of the beam, about a
#: receiver's gain stability (dG/G, 1e-4..1e-3); a smaller step measures no offset
MIN_STEP_BEAMS = 0.01
#: the largest correction a pointing model may make in the sky it is used in (deg): the
#: bound of an effect's arcsec parameter (10 deg, antsim.world.effects.base.NAME_BOUNDS),
#: beyond any telescope's pointing error; a larger one points the antenna away from every
#: source, and the campaign records nothing worth a fit
MAX_CORRECTION_DEG = 10.0


class PlanNotScenarioError(InputError):
    """A plan file read where a scenario belongs."""


@dataclass(frozen=True)
class EffectSpec:
    """An effect as configured: its catalogue name and validated parameters."""

    name: str
    params: dict[str, Any]


@dataclass(frozen=True)
class Scenario:
    """A validated scenario (units in the field names)."""

    name: str
    path: str
    description: str
    seed: int
    site: Site
    epoch_utc: str
    duration_s: float
    mount: MountConfig
    beam: BeamConfig
    receiver: ReceiverConfig
    atmosphere: AtmosphereConfig
    weather: WeatherConfig
    sources: tuple[SourceConfig, ...]
    truth_model: PointingModel
    effects: tuple[EffectSpec, ...]
    controller: ControllerConfig
    text: str = field(default="", repr=False)
    #: the TV camera of optical pointing (None: radio five-point scans only)
    camera: CameraConfig | None = None
    #: structure temperature sensors (None: none, as on the 1990 antenna)
    structure_sensors: SensorConfig | None = None

    def with_controller_model(self, model: PointingModel) -> Scenario:
        """The same scenario with another pointing model in use by the controller (on an
        equatorial mount the model's term names are re-bound to equatorial terms)."""
        if self.mount.kind == "equatorial":
            model = equatorial_model(model.names, self.site.latitude_deg,
                                     list(model.values_arcsec), model.name)
        return replace(self, controller=replace(self.controller, model=model))

    def with_effects(self, effects: tuple[EffectSpec, ...]) -> Scenario:
        return replace(self, effects=tuple(effects))

    def truth_arcsec(self, names) -> dict[str, float]:
        """The injected value (arcsec) of each fitted term of ``names``: the truth model's, 0
        where it has none; with structure sensors, the thermal terms' the thermal effect's
        (:func:`antsim.world.sensors.thermal_truth`). On an equatorial mount Crane's C5 is the
        world's refraction scale (:mod:`controller.pointing.crane`), not a term of the truth
        model: its truth is the ``refraction_anomaly`` effect's scale (1 without one), at 60"
        per unit."""
        truth = self.truth_model.as_dict()
        if self.structure_sensors is not None:  # thermal terms: the thermal effect's
            for effect in self.effects:
                if effect.name == "thermal":
                    truth = {**thermal_truth(effect.params), **truth}
        out = {n: float(truth.get(n, 0.0)) for n in names}
        if self.mount.kind == "equatorial" and REFRACTION_SCALE_TERM in out:
            scales = [e.params.get("scale", 1.0) for e in self.effects
                      if e.name == "refraction_anomaly"]
            out[REFRACTION_SCALE_TERM] = 60.0 * math.prod(scales)
        return out


# ---------------------------------------------------------------------------------------------
def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario file; raises InputError on the first bad value."""
    path = Path(path)
    root = load_toml(path)
    if "variants" in root:  # read as a scenario, it would lack a site
        raise PlanNotScenarioError(root.where, "variants", "[[variants]]",
                           "this file is a plan, not a scenario", "antsim plan runs a plan")
    text = root.text
    top = schema.ROOT
    name = top.read(root, "name")
    description = top.read(root, "description")
    seed = top.read(root, "seed")
    site = _site(_table(root, top, "site"))
    campaign = _table(root, top, "campaign")
    epoch = _epoch(campaign)
    duration_s = _duration_s(campaign, epoch)
    campaign.finish()
    mount = _mount(_table(root, top, "mount"))
    beam = _beam(_table(root, top, "beam"))
    receiver = _receiver(_table(root, top, "receiver"))
    atmosphere = _settings(_table(root, top, "atmosphere"), schema.ATMOSPHERE,
                           AtmosphereConfig)
    weather = _weather(_table(root, top, "weather"))
    camera_t = _table(root, top, "camera")
    camera = None if camera_t is None else _settings(camera_t, schema.CAMERA, CameraConfig)
    sources = tuple(_source(t) for t in root.tables("sources", top["sources"].default))
    stars_t = _table(root, top, "stars")
    if stars_t is not None:
        sources += _stars(stars_t)
    if not sources:
        raise root.error("sources", [], "the scenario lists no sources")
    names = [s.name for s in sources]
    repeated = duplicate(names)  # upper and lower case alike: a report or an option names it
    if repeated is not None:
        i, s = repeated
        raise root.error(f"sources[{i}].name", s, "duplicate source name")
    truth = _table(root, top, "truth")
    truth_model = _model(truth, schema.TRUTH, base=path.parent, mount=mount, site=site)
    effects = tuple(_effect(t, mount, site)
                    for t in truth.tables("effects", schema.TRUTH["effects"].default))
    _check_effect_sources(effects, names, truth)
    _check_clock(effects, duration_s, truth)
    truth.finish()
    sensors_t = _table(root, top, "structure_sensors")
    sensors = None if sensors_t is None else _sensors(sensors_t, mount)
    controller = _controller(_table(root, top, "controller"), site, epoch, duration_s,
                             sources, receiver, mount, name, path.parent, camera)
    for table, model in ((truth, truth_model), (root.table("controller", {}),
                                                 controller.model)):
        _check_correction(table, model, mount, controller.scheduler)
    if sensors is not None:
        if controller.method != "five_point":
            raise InputError(str(path), "structure_sensors", "(table)",
                             "the controller reads structure temperatures during cross scans; "
                             f"it points by {controller.method!r}",
                             "remove [structure_sensors]")
        controller = replace(controller, structure_sensors=sensors.names,
                             structure_lag_s=sensors.lag_s)
    root.finish()
    return Scenario(name=name, path=str(path), description=description, seed=seed, site=site,
                    epoch_utc=epoch, duration_s=duration_s, mount=mount, beam=beam,
                    receiver=receiver, atmosphere=atmosphere, weather=weather, sources=sources,
                    truth_model=truth_model, effects=effects, controller=controller, text=text,
                    camera=camera, structure_sensors=sensors)


def _table(t: Table, section: Section, name: str) -> Table | None:
    """The sub-table ``name`` of ``t`` as ``section`` declares it: required, optional with
    every key at its default (``{}``), or absent (None)."""
    key = section[name]
    if key.default is None and name not in t:
        t.raw(name, None)  # known here, for the unknown-key hint
        return None
    return t.table(name) if key.required else t.table(name, {})


def _settings(t: Table, section: Section, settings: type):
    """A settings dataclass made of every key of ``section`` (nothing checked between
    them)."""
    value = settings(**section.read_all(t))
    t.finish()
    return value


def _site(t: Table) -> Site:
    return _settings(t, schema.SITE, Site)


def _epoch(t: Table) -> str:
    """``start_utc`` as astropy's ISO UTC time (checked as :mod:`antsim.schema.utc` says)."""
    return utc_time(t, "start_utc", schema.CAMPAIGN.read(t, "start_utc"))


def _duration_s(t: Table, epoch: str) -> float:
    """``duration_h`` in seconds: the campaign ends where UTC is known."""
    hours = schema.CAMPAIGN.read(t, "duration_h")
    problem = end_problem(epoch, hours * 3600.0)
    if problem:
        raise t.error("duration_h", hours, problem)
    return hours * 3600.0


def _axis(t: Table, section: Section) -> AxisConfig:
    axis = AxisConfig(**section.read_all(t))
    if axis.max_deg <= axis.min_deg:
        raise t.error("max_deg", axis.max_deg, f"must exceed min_deg = {axis.min_deg:g}")
    # the sky is computed to EPHEMERIS_MARGIN_S past the campaign: a slew begun before the
    # end must arrive within it (real antennas cross their whole range in minutes)
    span = axis.max_deg - axis.min_deg
    slew_s = move_time_s(span, axis.speed_deg_s, axis.accel_deg_s2)
    if slew_s > EPHEMERIS_MARGIN_S:
        key = ("speed_deg_s" if span / axis.speed_deg_s > EPHEMERIS_MARGIN_S / 2
               else "accel_deg_s2")
        raise t.error(key, getattr(axis, key),
                      f"too slow: crossing the axis range ({span:g} deg) would take "
                      f"{slew_s:.3g} s, more than the {EPHEMERIS_MARGIN_S:g} s allowed")
    t.finish()
    return axis


def _mount(t: Table) -> MountConfig:
    keys = schema.MOUNT
    kind = keys.read(t, "kind")
    if kind == "equatorial":  # [mount.ha] and [mount.dec] name the axes
        az = _axis(t.table("ha"), schema.MOUNT_HA)
        el = _axis(t.table("dec"), schema.MOUNT_DEC)
        if not (-180.0 <= az.min_deg < 0.0 < az.max_deg <= 180.0):
            raise t.error("ha", [az.min_deg, az.max_deg],
                          "the hour-angle limits must lie within -180..180 deg around 0")
        if not (-90.0 <= el.min_deg < el.max_deg <= 90.0):
            raise t.error("dec", [el.min_deg, el.max_deg], "must lie within -90..90 deg")
    else:
        az = _axis(t.table("az", {}), schema.MOUNT_AZ)
        el = _axis(t.table("el", {}), schema.MOUNT_EL)
        if az.max_deg - az.min_deg < 360.0:
            raise t.error("az.max_deg", az.max_deg,
                          "the azimuth range must span at least 360 deg")
        if not (0.0 <= el.min_deg < 90.0):
            raise t.error("el.min_deg", el.min_deg, "must be in 0..90 deg")
        if el.max_deg > 90.0:
            raise t.error("el.max_deg", el.max_deg, "must be <= 90 deg")
    mount = MountConfig(kind=kind, az=az, el=el,
                        **keys.read_all(t, ("settle_s", "wrap_margin_s", "feed_speed_deg_s")))
    t.finish()
    return mount


def _beam(t: Table) -> BeamConfig:
    keys = schema.BEAM
    el = tuple(keys.read(t, "efficiency_el_deg"))
    eff = tuple(keys.read(t, "efficiency"))
    if len(el) != len(eff):
        raise t.error("efficiency", list(eff), f"needs {len(el)} values, one per efficiency_el_deg")
    if any(b <= a for a, b in pairwise(el)):
        raise t.error("efficiency_el_deg", list(el), "must increase")
    harmonics = None
    harmonics_t = _table(t, keys, "gain_harmonics")
    if harmonics_t is not None:  # Crane 1981: relative gain = Y00 + Y10 + Y11e + Y11o terms
        harmonics = tuple(schema.BEAM_GAIN_HARMONICS.read_all(harmonics_t).values())
        harmonics_t.finish()
    beam = BeamConfig(hpbw_arcmin=keys.read(t, "hpbw_arcmin"), efficiency_el_deg=el,
                      efficiency=eff, gain_k_per_jy=keys.read(t, "gain_k_per_jy"),
                      gain_harmonics=harmonics)
    t.finish()
    return beam


def _receiver(t: Table) -> ReceiverConfig:
    keys = schema.RECEIVER
    d = ReceiverConfig()
    channels = []
    for ct in t.tables("channels", [{"name": c.name, "tsys_k": c.tsys_k} for c in d.channels]):
        channel = ChannelConfig(**schema.CHANNEL.read_all(ct))
        # recordings name a scan's channels and their average (AVG) in one column
        if channel.name.upper() == AVERAGE_CHANNEL:
            raise ct.error("name", channel.name, "is the recordings' name of the channels' "
                           "average", "name the channel otherwise (XR, XL, ...)")
        if duplicate([c.name for c in channels] + [channel.name]) is not None:
            raise ct.error("name", channel.name, "names two channels (upper and lower case "
                           "alike): every scan would be recorded twice under it")
        channels.append(channel)
        ct.finish()
    if not channels:
        raise t.error("channels", [], "the receiver needs at least one channel")
    frequency_ghz = keys.read(t, "frequency_ghz")
    # a band wider than twice its centre frequency would reach below 0 Hz
    widest = 2000.0 * frequency_ghz
    if keys.read(t, "radiometer_noise"):
        bandwidth = keys.read(t, "bandwidth_mhz")
        if bandwidth > widest:
            raise t.error("bandwidth_mhz", bandwidth,
                          f"must be <= {widest:g} (twice frequency_ghz: a wider band would "
                          "reach below 0 Hz)", "radiometer_noise = false leaves the noise out")
    elif "bandwidth_mhz" in t:
        raise t.error("bandwidth_mhz", t.raw("bandwidth_mhz"),
                      "not with radiometer_noise = false (no radiometer, no bandwidth)")
    else:
        bandwidth = NO_RADIOMETER_BANDWIDTH_MHZ
    rec = ReceiverConfig(
        channels=tuple(channels), frequency_ghz=frequency_ghz, bandwidth_mhz=bandwidth,
        **keys.read_all(t, ("sample_interval_s", "gain_fluctuation", "gain_timescale_s")))
    t.finish()
    return rec


def _weather(t: Table) -> WeatherConfig:
    w = WeatherConfig(**schema.WEATHER.read_all(t))
    if w.air_max_c < w.air_min_c:
        raise t.error("air_max_c", w.air_max_c, f"is below air_min_c = {w.air_min_c:g}")
    if w.min_local_h == w.max_local_h:
        raise t.error("max_local_h", w.max_local_h, "must differ from min_local_h")
    t.finish()
    return w


def _angle(t: Table, key: str, unit: str) -> float:
    """An angle in degrees from ``key_deg`` (number) or ``key`` (sexagesimal string)."""
    keys = schema.SOURCE
    if f"{key}_deg" in t:
        return keys.read(t, f"{key}_deg")
    text = keys.read(t, key)
    try:
        value = Angle(text, unit=unit).deg
    except Exception:  # astropy raises several types for unparseable angles
        example = "03h16m29.6s" if unit == "hourangle" else "+41d19m52s"
        raise t.error(key, text, "not an angle", f"write e.g. {example}") from None
    lo, hi = keys[key].min, keys[key].max
    if not lo <= value <= hi:
        raise t.error(key, text, f"must be within {lo:g}..{hi:g} deg")
    return float(value)


def _source(t: Table) -> SourceConfig:
    keys = schema.SOURCE
    src = SourceConfig(
        name=keys.read(t, "name"),
        ra_deg=_angle(t, "ra", "hourangle"),
        dec_deg=_angle(t, "dec", "deg"),
        **keys.read_all(t, ("frame", "flux_jy", "size_arcmin", "note")),
    )
    t.finish()
    return src


def _model(t: Table, keys: Section, base: Path, mount: MountConfig | None = None,
           site: Site | None = None) -> PointingModel:
    """A pointing model from ``model`` (named, or a .mod/.json file) and ``terms``; on an
    equatorial mount from TPOINT's equatorial terms (:mod:`controller.pointing.equatorial`)."""
    spec = keys.read(t, "model")
    if not spec.strip():  # as a path, it would name the scenario's own directory
        raise t.error("model", spec, "is empty",
                      f"give a named model ({', '.join(sorted(NAMED_MODELS))}) or a file")
    scale = UNIT_ARCSEC[keys.read(t, "units")]
    values_table = t.table("terms", {})
    bounds = keys["terms"]
    values: dict[str, float] = {}
    equatorial = mount is not None and mount.kind == "equatorial"
    given: dict[str, str] = {}
    for key in values_table:
        try:
            term = (equatorial_term(key, site.latitude_deg) if equatorial else get_term(key))
        except TermError as err:
            raise values_table.error(key, values_table.raw(key), "not a pointing term",
                                     str(err)) from None
        if term.name in given:
            raise values_table.error(key, values_table.raw(key), f"gives the term "
                                     f"{term.name} again (first as {given[term.name]})",
                                     "give each term once")
        given[term.name] = key
        values[term.name] = values_table.number(key, min=bounds.min / scale,
                                                max=bounds.max / scale) * scale
    values_table.finish()
    if equatorial:
        if spec not in EQUATORIAL_MODELS:
            raise t.error("model", spec, "not a named equatorial model",
                          f"equatorial models: {', '.join(sorted(EQUATORIAL_MODELS))}")
        model = equatorial_model(spec, site.latitude_deg)
    elif spec in NAMED_MODELS:
        model = PointingModel(spec)
    else:
        model = _model_file(t, spec, base)
    thermal = thermal_terms_of(model)
    if thermal:
        raise t.error("model", spec, f"has thermal terms ({', '.join(thermal)}), which need "
                      "structure temperatures at every instant",
                      "the thermal effect is a [[truth.effects]] table; fit thermal terms, "
                      "do not give them as a model")
    unknown = set(values) - set(model.names)
    if unknown:
        name = sorted(unknown)[0]
        raise values_table.error(name, values[name] / scale,
                                 f"is not a term of model {model.name!r}",
                                 f"its terms are {' '.join(model.names) or '(none)'}")
    return model.with_values(values) if values else model


@dataclass(frozen=True)
class Overcorrection:
    """A pointing model that moves the pointing by more than :data:`MAX_CORRECTION_DEG`:
    the term that moves it most where it moves it most, and what is wrong."""

    term: str
    value_arcsec: float
    problem: str


def overcorrection(model: PointingModel, mount: MountConfig,
                   scheduler: SchedulerConfig) -> Overcorrection | None:
    """Whether ``model`` is no telescope's pointing model: a correction on the sky larger
    than :data:`MAX_CORRECTION_DEG` somewhere the scheduler observes (on an equatorial
    mount, within the axes' limits); None when there is none."""
    if not len(model):
        return None
    if mount.kind == "equatorial":
        axis1 = np.linspace(mount.az.min_deg, mount.az.max_deg, 37)
        axis2 = np.linspace(max(mount.el.min_deg, -89.0), min(mount.el.max_deg, 89.0), 19)
        names = ("hour angle", "declination")
    else:  # every 10 deg of azimuth, 16 elevations: the bound is coarse, so is the grid
        axis1 = np.arange(0.0, 360.0, 10.0)
        axis2 = np.linspace(scheduler.elevation_min_deg, scheduler.elevation_max_deg, 16)
        names = ("azimuth", "elevation")
    a1, a2 = (np.radians(g).ravel() for g in np.meshgrid(axis1, axis2))
    feed = np.zeros_like(a1) if model.needs_feed else None
    d1, d2 = model.offset_rad(a1, a2, feed)
    sky_deg = np.degrees(np.hypot(d1 * np.cos(a2), d2))
    worst = int(np.argmax(sky_deg))
    if not sky_deg[worst] > MAX_CORRECTION_DEG:
        return None
    # the term that moves it most there
    basis1, basis2 = model.design_matrix(a1[worst:worst + 1], a2[worst:worst + 1],
                                         None if feed is None else feed[:1])
    coeff = np.asarray(model.values_arcsec, dtype=float)
    share = np.hypot(basis1[0] * coeff * math.cos(a2[worst]), basis2[0] * coeff)
    term = model.names[int(np.argmax(share))]
    return Overcorrection(term, float(model[term]), (
        f"moves the pointing by {sky_deg[worst]:.3g} deg at {names[0]} "
        f"{np.degrees(a1[worst]):.0f}, {names[1]} {np.degrees(a2[worst]):.0f} deg (most of it "
        f"{term} = {model[term]:g}\"): more than any telescope's pointing error "
        f"({MAX_CORRECTION_DEG:g} deg)"))


def _check_correction(t: Table, model: PointingModel, mount: MountConfig,
                      scheduler: SchedulerConfig) -> None:
    """The truth model or the model in use (``model``, of table ``t``) moves the pointing by
    no more than any telescope's pointing error; the line names the term as the table gives
    it (or the model, from a file or a name)."""
    found = overcorrection(model, mount, scheduler)
    if found is None:
        return
    terms = t.data.get("terms", {})
    key = next((k for k in terms if k.upper() == found.term), None)
    if key is not None:
        raise InputError(t.where, f"{t.key('terms')}.{key}", terms[key], found.problem,
                         "check the value and the table's units")
    raise InputError(t.where, t.key("model"), t.data.get("model", model.name), found.problem,
                     "check the model's values and their units")


def thermal_terms_of(model: PointingModel) -> list[str]:
    """The model's terms in recorded quantities (structure temperatures, proxies): a truth
    model and the controller's model in use must be functions of the position alone."""
    return [t.name for t in model.terms if thermal_regressors((t,))]


def _sensors(t: Table, mount: MountConfig) -> SensorConfig:
    """``[structure_sensors]``: which sensors, their noise, resolution and lag, and how far a
    sensor's member departs from its part's mean in sunshine (antsim.world.sensors)."""
    if mount.kind != "altaz":
        raise t.error("names", "(table)", "structure sensors are modelled on an alt-az "
                      "antenna's dish, yoke and pedestal", "remove [structure_sensors]")
    keys = schema.STRUCTURE_SENSORS
    names = tuple(keys.read(t, "names"))
    for i, name in enumerate(names):
        if name not in STRUCTURE_SENSORS:
            raise t.error("names", name, "unknown structure temperature sensor",
                          f"sensors are {', '.join(STRUCTURE_SENSORS)}")
        if names.index(name) != i:
            raise t.error("names", name, "listed more than once")
    if not names:
        raise t.error("names", [], "lists no sensor", "remove [structure_sensors] instead")
    config = SensorConfig(names=names, **keys.read_all(
        t, ("noise_k", "resolution_k", "lag_s", "local_k", "local_timescale_s")))
    t.finish()
    return config


def _model_file(t: Table, spec: str, base: Path) -> PointingModel:
    path = Path(spec)
    if not path.is_absolute():
        path = base / path
    if not path.exists():
        raise t.error("model", spec, "neither a named model nor an existing file",
                      f"named models: {', '.join(sorted(NAMED_MODELS))}")
    return load_model(path)


def _effect(t: Table, mount: MountConfig | None = None, site: Site | None = None) -> EffectSpec:
    name = t.string("effect")
    cls = EFFECTS.get(name)
    if cls is None:
        raise t.error("effect", name, "unknown effect",
                      f"known effects: {', '.join(sorted(EFFECTS))}")
    equatorial = mount is not None and mount.kind == "equatorial"
    if equatorial and name not in EQUATORIAL_EFFECTS:
        raise t.error("effect", name, "models an alt-az mount; not available on an "
                      "equatorial mount", f"use truth.terms or: {', '.join(EQUATORIAL_EFFECTS)}")
    if not equatorial and name in EQUATORIAL_ONLY_EFFECTS:
        raise t.error("effect", name, "models an equatorial mount; not available on an "
                      "alt-az mount")
    if name == "terms":
        if equatorial:  # the mount's own vocabulary (controller.pointing.equatorial)
            effect = cls.from_table(t, lambda n: equatorial_term(n, site.latitude_deg))
        else:
            effect = cls.from_table(t)
        return EffectSpec(name, {"terms_arcsec": dict(effect.values_arcsec)})
    effect = cls.from_table(t)
    return EffectSpec(name, effect.params())


def _check_clock(effects, duration_s: float, truth: Table) -> None:
    """A clock error at most the hour the simulated sky reaches beyond the campaign (the
    world computes the sky at the true time of the antenna's clock)."""
    for i, spec in enumerate(effects):
        if spec.name != "clock_error":
            continue
        worst = (abs(spec.params["offset_s"])
                 + abs(spec.params["drift_s_per_day"]) * duration_s / 86400.0)
        if worst > EPHEMERIS_MARGIN_S:
            raise InputError(truth.where, f"truth.effects[{i}].offset_s",
                             spec.params["offset_s"],
                             f"with drift_s_per_day = {spec.params['drift_s_per_day']:g} the "
                             f"clock is {worst:.4g} s off by the campaign's end; at most "
                             f"{EPHEMERIS_MARGIN_S:g} s")


def _check_effect_sources(effects, names, truth: Table) -> None:
    for i, spec in enumerate(effects):
        source = spec.params.get("source")
        if source is not None and source not in names:
            raise InputError(truth.where, f"truth.effects[{i}].source", source,
                             "unknown source", f"sources are {', '.join(names)}")


def check_scan(scan: ScanConfig, sample_interval_s: float, error) -> None:
    """The scan's settings against each other and the receiver's sampling; ``error(key,
    value, problem, hint="")`` makes the line naming the key where it is written (a
    scenario's ``[controller.scan]``, a plan's variant)."""
    # the noise of an integration is the scatter of its samples: two at least
    fewest = 2.0 * sample_interval_s
    if scan.integration_s < fewest:
        raise error("integration_s", scan.integration_s, f"must be >= {fewest:g}",
                    f"two samples of receiver.sample_interval_s = {sample_interval_s:g} s")
    samples = scan.integration_s / sample_interval_s
    if samples > MAX_SAMPLES:
        raise error("integration_s", scan.integration_s,
                    f"holds {samples:.3g} samples of receiver.sample_interval_s = "
                    f"{sample_interval_s:g} s; at most {MAX_SAMPLES:g}",
                    "integrate less or sample less often")
    if scan.step_arcmin > 1.2 * scan.hpbw_arcmin:
        raise error("step_arcmin", scan.step_arcmin,
                    f"the +-D points would lie outside the main beam (HPBW "
                    f"{scan.hpbw_arcmin:g}')", f"use at most {1.2 * scan.hpbw_arcmin:.1f}'")
    smallest = scan.hpbw_arcmin * MIN_STEP_BEAMS
    if scan.step_arcmin < smallest:
        raise error("step_arcmin", scan.step_arcmin,
                    f"must be >= {smallest:.3g}: a step below {MIN_STEP_BEAMS:g} of the beam "
                    f"(HPBW {scan.hpbw_arcmin:g}') changes the power by less than 3 parts "
                    "in 10,000, which no scan measures")


def _controller(t: Table, site: Site, epoch: str, duration_s: float, sources, receiver,
                mount: MountConfig, scenario_name: str, base: Path,
                camera: CameraConfig | None = None) -> ControllerConfig:
    keys = schema.CONTROLLER
    model = _model(t, keys, base=base, mount=mount, site=site)
    names = [s.name for s in sources]
    scan_t = _table(t, keys, "scan")
    scan = ScanConfig(**schema.SCAN.read_all(scan_t))
    check_scan(scan, receiver.sample_interval_s, scan_t.error)
    scan_t.finish()
    sched_t = _table(t, keys, "scheduler")
    sched_keys = schema.SCHEDULER
    chosen = tuple(sched_keys.read(sched_t, "sources"))
    for s in chosen:
        if s not in names:
            raise sched_t.error("sources", s, "unknown source", f"sources are {', '.join(names)}")
    sched = SchedulerConfig(
        **sched_keys.read_all(sched_t, ("policy", "elevation_min_deg", "elevation_max_deg",
                                        "min_revisit_s", "slew_weight", "window")),
        sources=chosen,
        hour_angle_limit_deg=(
            sched_keys.read(sched_t, "hour_angle_limit_deg",
                            default=min(-mount.az.min_deg, mount.az.max_deg) - 2.0)
            if mount.kind == "equatorial" else None),
        declination_max_deg=sched_keys.read(sched_t, "declination_max_deg"),
    )
    if sched.elevation_max_deg <= sched.elevation_min_deg:
        raise sched_t.error("elevation_max_deg", sched.elevation_max_deg,
                            f"must exceed elevation_min_deg = {sched.elevation_min_deg:g}")
    lowest = sched.elevation_min_deg - 4.0 * scan.step_arcmin / 60.0
    if lowest < mount.el.min_deg:
        raise InputError(t.where, "controller.scan.step_arcmin", scan.step_arcmin,
                         f"the -4D point at the lowest scheduled elevation "
                         f"({sched.elevation_min_deg:g} deg) falls below the mount's limit "
                         f"({mount.el.min_deg:g} deg)",
                         "use a smaller step or raise controller.scheduler.elevation_min_deg")
    sched_t.finish()
    search = _settings(_table(t, keys, "search"), schema.SEARCH, SearchConfig)
    refraction = keys.read(t, "refraction")
    fit_terms, fit_name = _fit_spec(t, mount, site)
    fit_fixed = _fit_fixed(t, fit_terms)
    method = keys.read(t, "method")
    if method == "optical" and camera is None:
        raise t.error("method", method, "optical pointing needs a [camera] table")
    if camera is not None and method != "optical":
        raise t.error("method", method, "a scenario with a [camera] points optically",
                      'set controller.method = "optical"')
    feed_angles = tuple(keys.read(t, "feed_angles_deg"))
    tipping_t, sky_t, optical_t, gain_t = (_table(t, keys, name) for name in
                                           ("tipping", "sky", "optical", "gain_curve"))
    tipping = None if tipping_t is None else _tipping(tipping_t)
    sky = None if sky_t is None else _settings(sky_t, schema.SKY, SkyConfig)
    optical = (_settings(optical_t, schema.OPTICAL, OpticalConfig) if optical_t is not None
               else OpticalConfig() if method == "optical" else None)
    gain_curve = None if gain_t is None else _gain_curve(gain_t, names)
    # what "night" means for the campaign's night window and its night fit (E)
    night = keys.read(t, "night_sun_max_deg")
    t.finish()
    catalog = tuple(CatalogSource(s.name, s.ra_deg, s.dec_deg, s.frame, s.flux_jy,
                                  s.size_arcmin) for s in sources)
    return ControllerConfig(
        site_latitude_deg=site.latitude_deg, site_longitude_deg=site.longitude_deg,
        site_height_m=site.height_m, epoch_utc=epoch, duration_s=duration_s, sources=catalog,
        model=model, scan=scan, scheduler=sched, search=search, refraction=refraction,
        frequency_ghz=(camera.frequency_ghz if camera is not None and method == "optical"
                       else receiver.frequency_ghz),
        scenario_name=scenario_name, site_name=site.name,
        fit_terms=fit_terms, fit_model_name=fit_name, fit_fixed=fit_fixed, mount=mount.kind,
        method=method,
        feed_angles_deg=feed_angles, tipping=tipping, sky=sky, optical=optical,
        gain_curve=gain_curve, night_sun_max_deg=night)


def _fit_spec(t: Table, mount: MountConfig | None = None,
              site: Site | None = None) -> tuple[tuple[str, ...], str]:
    """``fit_model``: a named model or a comma-separated list of terms (default: none)."""
    spec = schema.CONTROLLER.read(t, "fit_model")
    if not spec:
        return (), ""
    lookup = get_term
    named = NAMED_MODELS
    if mount is not None and mount.kind == "equatorial":
        named = EQUATORIAL_MODELS

        def lookup(n: str):
            return equatorial_term(n, site.latitude_deg)
    if spec in named:
        return named[spec], spec
    names = tuple(n.strip().upper() for n in spec.split(",") if n.strip())
    for n in names:
        try:
            lookup(n)
        except TermError as err:
            raise t.error("fit_model", spec, f"{n} is not a pointing term", str(err)) from None
    return names, "custom"


def _fit_fixed(t: Table, fit_terms: tuple[str, ...]) -> tuple[tuple[str, float], ...]:
    """``fit_fixed``: terms of ``fit_model`` held at a value (in the table's ``units``)."""
    if "fit_fixed" not in t:
        return ()
    keys = schema.CONTROLLER
    scale = UNIT_ARCSEC[keys.read(t, "units")]
    bounds = keys["fit_fixed"]
    fixed_t = t.table("fit_fixed")
    out = []
    given: dict[str, str] = {}
    for key in fixed_t:
        name = key.strip().upper()
        if name not in fit_terms:
            raise fixed_t.error(key, fixed_t.raw(key), "is not a term of controller.fit_model",
                                f"its terms are {' '.join(fit_terms) or '(none given)'}")
        if name in given:
            raise fixed_t.error(key, fixed_t.raw(key), f"holds the term {name} again (first "
                                f"as {given[name]})", "give each term once")
        given[name] = key
        out.append((name, fixed_t.number(key, min=bounds.min / scale,
                                         max=bounds.max / scale) * scale))
    fixed_t.finish()
    return tuple(out)


def _stars(t: Table) -> tuple[SourceConfig, ...]:
    """``[stars]``: ``count`` synthetic bright stars above ``dec_min_deg`` (antsim.world.camera)."""
    keys = schema.STARS
    count = keys.read(t, "count")
    dec_min = keys.read(t, "dec_min_deg")
    t.finish()
    return tuple(SourceConfig(name, ra, dec, "icrs", 1.0, 0.0, "synthetic bright star")
                 for name, ra, dec in synthetic_stars(count, dec_min))


def _tipping(t: Table) -> TippingConfig:
    tip = TippingConfig(**schema.TIPPING.read_all(t))
    if len(set(tip.elevations_deg)) < 3:
        raise t.error("elevations_deg", list(tip.elevations_deg),
                      "needs at least three different elevations")
    t.finish()
    return tip


def _gain_curve(t: Table, names: list[str]) -> GainCurveConfig:
    keys = schema.GAIN_CURVE
    sources = tuple(keys.read(t, "sources"))
    for s in sources:
        if s not in names:
            raise t.error("sources", s, "unknown source", f"sources are {', '.join(names)}")
    knots = tuple(keys.read(t, "knots_deg"))
    if any(b <= a for a, b in pairwise(knots)):
        raise t.error("knots_deg", list(knots), "must increase")
    gc = GainCurveConfig(sources=sources, knots_deg=knots,
                         **keys.read_all(t, ("kind", "zenith_opacity", "t_atm_k")))
    t.finish()
    return gc
