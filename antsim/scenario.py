"""Scenarios: TOML files describing a complete, runnable situation, loaded and validated.

A scenario names the telescope and its site, the campaign window, the sources, the injected
truth (a pointing model plus a list of physical effects), the receiver, beam, atmosphere and
weather, and the control program's own settings (the pointing model in use, the scan, the
scheduler). Every bad value becomes one :class:`~controller.errors.InputError` line naming the
file, the key and the value; unknown keys are errors too. See ``scenarios/ghigo1990.toml``.

Beyond the 45-ft (``docs/telescopes.md``): ``mount.kind = "equatorial"`` (axes hour angle and
declination; models in TPOINT's equatorial terms, e.g. ``crane11``), ``beam.gain_harmonics``,
``[camera]`` and ``[stars]`` for optical pointing (``controller.method = "optical"``), and
``controller.feed_angles_deg``, ``[controller.tipping]``, ``[controller.gain_curve]``,
``[controller.optical]``.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace
from itertools import pairwise
from pathlib import Path
from typing import Any

from controller.astro.site import Site
from controller.astro.sun import NIGHT_SUN_MAX_DEG
from controller.errors import InputError
from controller.pointing.model import NAMED_MODELS, PointingModel
from controller.pointing.modelio import MAX_VALUE_ARCSEC
from controller.pointing.terms import TermError, get_term
from controller.program.config import (
    CatalogSource,
    ControllerConfig,
    OpticalConfig,
    SchedulerConfig,
    SearchConfig,
)
from controller.scans.config import GainCurveConfig, ScanConfig, SkyConfig, TippingConfig
from controller.scans.gaincurve import HARMONIC_NAMES

from .tomlcheck import Table, load_toml
from .world.atmosphere import AtmosphereConfig
from .world.beam import BeamConfig
from .world.camera import CameraConfig, synthetic_stars
from .world.effects import EFFECTS
from .world.mount import AxisConfig, MountConfig, move_time_s
from .world.receiver import ChannelConfig, ReceiverConfig
from .world.sensors import SensorConfig
from .world.sky import SourceConfig
from .world.weather import WeatherConfig

__all__ = ["EffectSpec", "Scenario", "load_scenario"]

UNIT_ARCSEC = {"arcsec": 1.0, "arcmin": 60.0, "deg": 3600.0}
ESTIMATORS = ("clark", "lsq")
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
#: longest correlation time of a random process (s): about 3 years; beyond it a process is a
#: constant, and its one-step correlation rounds to 1 (a division by zero)
MAX_TIMESCALE_S = 1e8
#: most receiver samples in one integration (each is a few numbers per channel in memory)
MAX_SAMPLES = 100_000


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
            from controller.pointing.equatorial import equatorial_model

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
        from controller.pointing.crane import REFRACTION_SCALE_TERM

        truth = self.truth_model.as_dict()
        if self.structure_sensors is not None:  # thermal terms: the thermal effect's
            from .world.sensors import thermal_truth

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
    text = root.text
    name = root.string("name")
    description = root.string("description", "")
    seed = root.integer("seed", 1, min=0)
    site = _site(root.table("site"))
    campaign = root.table("campaign")
    epoch = _epoch(campaign)
    duration_s = campaign.number("duration_h", gt=0.0, max=24.0 * 366) * 3600.0
    campaign.finish()
    mount = _mount(root.table("mount", {}))
    beam = _beam(root.table("beam", {}))
    receiver = _receiver(root.table("receiver", {}))
    atmosphere = _atmosphere(root.table("atmosphere", {}))
    weather = _weather(root.table("weather", {}))
    camera = _camera(root.table("camera")) if "camera" in root else None
    sources = tuple(_source(t) for t in root.tables("sources", []))
    if "stars" in root:
        sources += _stars(root.table("stars"))
    if not sources:
        raise root.error("sources", [], "the scenario lists no sources")
    names = [s.name for s in sources]
    for i, s in enumerate(names):
        if names.index(s) != i:
            raise root.error(f"sources[{i}].name", s, "duplicate source name")
    truth = root.table("truth", {})
    truth_model = _model(truth, default="none", base=path.parent, mount=mount, site=site)
    effects = tuple(_effect(t, mount, site) for t in truth.tables("effects", []))
    _check_effect_sources(effects, names, truth)
    _check_clock(effects, duration_s, truth)
    truth.finish()
    sensors = (_sensors(root.table("structure_sensors"), mount)
               if "structure_sensors" in root else None)
    controller = _controller(root.table("controller", {}), site, epoch, duration_s, sources,
                             receiver, mount, name, path.parent, camera)
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


def _site(t: Table) -> Site:
    site = Site(
        latitude_deg=t.number("latitude_deg", min=-90.0, max=90.0),
        longitude_deg=t.number("longitude_deg", min=-180.0, max=360.0),
        height_m=t.number("height_m", min=-500.0, max=9000.0),
        name=t.string("name", ""),
    )
    t.finish()
    return site


def _epoch(t: Table) -> str:
    text = t.string("start_utc")
    from astropy.time import Time

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # ERFA's "dubious year": refused below, by name
            epoch = Time(text, scale="utc")
            iso, year = epoch.isot, epoch.ymdhms["year"]
    except (ValueError, TypeError):
        raise t.error("start_utc", text, "not an ISO UTC time",
                      "write e.g. 1990-02-08T17:00:00") from None
    if not 1900 <= year <= 2200:
        raise t.error("start_utc", text, "year outside 1900..2200")
    return iso


def _axis(t: Table, default: AxisConfig) -> AxisConfig:
    axis = AxisConfig(
        speed_deg_s=t.number("speed_deg_s", default.speed_deg_s, gt=0.0, max=30.0),
        accel_deg_s2=t.number("accel_deg_s2", default.accel_deg_s2, gt=0.0, max=30.0),
        min_deg=t.number("min_deg", default.min_deg),
        max_deg=t.number("max_deg", default.max_deg),
    )
    if axis.max_deg <= axis.min_deg:
        raise t.error("max_deg", axis.max_deg, f"must exceed min_deg = {axis.min_deg:g}")
    # the sky is computed to EPHEMERIS_MARGIN_S past the campaign: a slew begun before the
    # end must arrive within it (real antennas cross their whole range in minutes)
    from controller.program.campaign import EPHEMERIS_MARGIN_S

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


def _wrap_margin(t: Table, default: float) -> float:
    """The cable-wrap look-ahead (s): within the hour the simulated sky reaches past the
    campaign (``EPHEMERIS_MARGIN_S``), as a slew's arrival is (:func:`_axis`)."""
    from controller.program.campaign import EPHEMERIS_MARGIN_S

    value = t.number("wrap_margin_s", default, min=0.0)
    if value > EPHEMERIS_MARGIN_S:
        raise t.error("wrap_margin_s", value,
                      f"must be <= {EPHEMERIS_MARGIN_S:g} s: the mount plans its cable wrap "
                      "at most that far ahead of a slew's arrival")
    return value


def _mount(t: Table) -> MountConfig:
    d = MountConfig()
    kind = t.string("kind", d.kind, choices=("altaz", "equatorial"))
    if kind == "equatorial":  # [mount.ha] and [mount.dec] name the axes
        az = _axis(t.table("ha"), d.az)
        el = _axis(t.table("dec"), d.el)
        if not (-180.0 <= az.min_deg < 0.0 < az.max_deg <= 180.0):
            raise t.error("ha", [az.min_deg, az.max_deg],
                          "the hour-angle limits must lie within -180..180 deg around 0")
        if not (-90.0 <= el.min_deg < el.max_deg <= 90.0):
            raise t.error("dec", [el.min_deg, el.max_deg], "must lie within -90..90 deg")
    else:
        az = _axis(t.table("az", {}), d.az)
        el = _axis(t.table("el", {}), d.el)
        if az.max_deg - az.min_deg < 360.0:
            raise t.error("az.max_deg", az.max_deg,
                          "the azimuth range must span at least 360 deg")
        if not (0.0 <= el.min_deg < 90.0):
            raise t.error("el.min_deg", el.min_deg, "must be in 0..90 deg")
        if el.max_deg > 90.0:
            raise t.error("el.max_deg", el.max_deg, "must be <= 90 deg")
    mount = MountConfig(kind=kind, az=az, el=el,
                        settle_s=t.number("settle_s", d.settle_s, min=0.0, max=600.0),
                        wrap_margin_s=_wrap_margin(t, d.wrap_margin_s),
                        # a full turn of the feed box (720 deg) within the same hour
                        feed_speed_deg_s=t.number("feed_speed_deg_s", d.feed_speed_deg_s,
                                                  min=0.2, max=90.0))
    t.finish()
    return mount


def _beam(t: Table) -> BeamConfig:
    d = BeamConfig()
    el = tuple(t.numbers("efficiency_el_deg", list(d.efficiency_el_deg), min_length=1))
    eff = tuple(t.numbers("efficiency", list(d.efficiency), min_length=1))
    if len(el) != len(eff):
        raise t.error("efficiency", list(eff), f"needs {len(el)} values, one per efficiency_el_deg")
    if any(b <= a for a, b in pairwise(el)):
        raise t.error("efficiency_el_deg", list(el), "must increase")
    if any(not 0.0 < e <= 1.5 for e in eff):
        raise t.error("efficiency", list(eff), "values must be in (0, 1.5]")
    harmonics = None
    if "gain_harmonics" in t:  # Crane 1981: relative gain = Y00 + Y10 + Y11e + Y11o terms
        h = t.table("gain_harmonics")
        harmonics = tuple(h.number(n, 0.0, min=-2.0, max=2.0) for n in HARMONIC_NAMES)
        h.finish()
    beam = BeamConfig(
        # 0.01' (0.6"): narrower than any radio telescope's beam
        hpbw_arcmin=t.number("hpbw_arcmin", d.hpbw_arcmin, min=0.01, max=600.0),
        efficiency_el_deg=el, efficiency=eff,
        gain_k_per_jy=t.number("gain_k_per_jy", d.gain_k_per_jy, gt=0.0, max=100.0),
        gain_harmonics=harmonics,
    )
    t.finish()
    return beam


def _receiver(t: Table) -> ReceiverConfig:
    d = ReceiverConfig()
    channels = []
    for ct in t.tables("channels", [{"name": c.name, "tsys_k": c.tsys_k} for c in d.channels]):
        channels.append(ChannelConfig(
            ct.string("name"), ct.number("tsys_k", gt=0.0, max=1e5),
            ct.number("gain_fluctuation", None, min=0.0, max=0.1, allow_none=True),
            ct.number("gain_k_per_jy", None, gt=0.0, max=100.0, allow_none=True)))
        ct.finish()
    if not channels:
        raise t.error("channels", [], "the receiver needs at least one channel")
    frequency_ghz = t.number("frequency_ghz", d.frequency_ghz, gt=0.0, max=1000.0)
    # a band wider than twice its centre frequency would reach below 0 Hz
    widest = 2000.0 * frequency_ghz
    if t.boolean("radiometer_noise", True):
        bandwidth = t.number("bandwidth_mhz", d.bandwidth_mhz, gt=0.0)
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
        channels=tuple(channels),
        frequency_ghz=frequency_ghz,
        bandwidth_mhz=bandwidth,
        # at least 0.01 s: a sample per 10 ms keeps an hour-long integration's arrays small
        sample_interval_s=t.number("sample_interval_s", d.sample_interval_s, min=0.01,
                                   max=60.0),
        gain_fluctuation=t.number("gain_fluctuation", d.gain_fluctuation, min=0.0, max=0.1),
        gain_timescale_s=t.number("gain_timescale_s", d.gain_timescale_s, gt=0.0,
                                  max=MAX_TIMESCALE_S),
    )
    t.finish()
    return rec


def _atmosphere(t: Table) -> AtmosphereConfig:
    d = AtmosphereConfig()
    atm = AtmosphereConfig(
        zenith_opacity=t.number("zenith_opacity", d.zenith_opacity, min=0.0, max=5.0),
        temperature_k=t.number("temperature_k", d.temperature_k, gt=0.0, max=400.0),
    )
    t.finish()
    return atm


def _weather(t: Table) -> WeatherConfig:
    d = WeatherConfig()
    w = WeatherConfig(
        air_min_c=t.number("air_min_c", d.air_min_c, min=-90.0, max=60.0),
        air_max_c=t.number("air_max_c", d.air_max_c, min=-90.0, max=60.0),
        min_local_h=t.number("min_local_h", d.min_local_h, min=0.0, lt=24.0),
        max_local_h=t.number("max_local_h", d.max_local_h, min=0.0, lt=24.0),
        wander_rms_c=t.number("wander_rms_c", d.wander_rms_c, min=0.0, max=20.0),
        wander_timescale_s=t.number("wander_timescale_s", d.wander_timescale_s, gt=0.0,
                                    max=MAX_TIMESCALE_S),
        pressure_hpa=t.number("pressure_hpa", d.pressure_hpa, min=100.0, max=1100.0),
        relative_humidity=t.number("relative_humidity", d.relative_humidity, min=0.0, max=1.0),
        wind_speed_m_s=t.number("wind_speed_m_s", d.wind_speed_m_s, min=0.0, max=60.0),
        wind_day_m_s=t.number("wind_day_m_s", d.wind_day_m_s, min=0.0, max=60.0,
                              allow_none=True),
    )
    if w.air_max_c < w.air_min_c:
        raise t.error("air_max_c", w.air_max_c, f"is below air_min_c = {w.air_min_c:g}")
    if w.min_local_h == w.max_local_h:
        raise t.error("max_local_h", w.max_local_h, "must differ from min_local_h")
    t.finish()
    return w


def _angle(t: Table, key: str, unit: str, lo: float, hi: float) -> float:
    """An angle in degrees from ``key_deg`` (number) or ``key`` (sexagesimal string)."""
    if f"{key}_deg" in t:
        return t.number(f"{key}_deg", min=lo, max=hi)
    text = t.string(key)
    from astropy.coordinates import Angle

    try:
        value = Angle(text, unit=unit).deg
    except Exception:  # astropy raises several types for unparseable angles
        example = "03h16m29.6s" if unit == "hourangle" else "+41d19m52s"
        raise t.error(key, text, "not an angle", f"write e.g. {example}") from None
    if not lo <= value <= hi:
        raise t.error(key, text, f"must be within {lo:g}..{hi:g} deg")
    return float(value)


def _source(t: Table) -> SourceConfig:
    src = SourceConfig(
        name=t.string("name"),
        ra_deg=_angle(t, "ra", "hourangle", 0.0, 360.0),
        dec_deg=_angle(t, "dec", "deg", -90.0, 90.0),
        frame=t.string("frame", "fk4", choices=("fk4", "fk5", "icrs")),
        flux_jy=t.number("flux_jy", gt=0.0, max=1e7),
        size_arcmin=t.number("size_arcmin", 0.0, min=0.0, max=600.0),
        note=t.string("note", ""),
    )
    if not src.name.strip():
        raise t.error("name", src.name, "must not be empty")
    t.finish()
    return src


def _model(t: Table, default: str, base: Path, mount: MountConfig | None = None,
           site: Site | None = None) -> PointingModel:
    """A pointing model from ``model`` (named, or a .mod/.json file) and ``terms``; on an
    equatorial mount from TPOINT's equatorial terms (:mod:`controller.pointing.equatorial`)."""
    spec = t.string("model", default)
    unit = t.string("units", "arcsec", choices=tuple(UNIT_ARCSEC))
    scale = UNIT_ARCSEC[unit]
    values_table = t.table("terms", {})
    values: dict[str, float] = {}
    equatorial = mount is not None and mount.kind == "equatorial"
    if equatorial:
        from controller.pointing.equatorial import (
            EQUATORIAL_MODELS,
            equatorial_model,
            equatorial_term,
        )
    for key in values_table:
        try:
            term = (equatorial_term(key, site.latitude_deg) if equatorial else get_term(key))
            # a coefficient within half a turn (the bound of model files, modelio)
            values[term.name] = values_table.number(key, min=-MAX_VALUE_ARCSEC / scale,
                                                    max=MAX_VALUE_ARCSEC / scale) * scale
        except TermError as err:
            raise values_table.error(key, values_table.raw(key), "not a pointing term",
                                     str(err)) from None
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


def thermal_terms_of(model: PointingModel) -> list[str]:
    """The model's terms in recorded quantities (structure temperatures, proxies): a truth
    model and the controller's model in use must be functions of the position alone."""
    from controller.pointing.thermal import thermal_regressors

    return [t.name for t in model.terms if thermal_regressors((t,))]


def _sensors(t: Table, mount: MountConfig) -> SensorConfig:
    """``[structure_sensors]``: which sensors, their noise, resolution and lag, and how far a
    sensor's member departs from its part's mean in sunshine (antsim.world.sensors)."""
    from controller.pointing.thermal import STRUCTURE_SENSORS

    if mount.kind != "altaz":
        raise t.error("names", "(table)", "structure sensors are modelled on an alt-az "
                      "antenna's dish, yoke and pedestal", "remove [structure_sensors]")
    d = SensorConfig()
    names = tuple(t.strings("names", list(d.names)))
    for i, name in enumerate(names):
        if name not in STRUCTURE_SENSORS:
            raise t.error("names", name, "unknown structure temperature sensor",
                          f"sensors are {', '.join(STRUCTURE_SENSORS)}")
        if names.index(name) != i:
            raise t.error("names", name, "listed more than once")
    if not names:
        raise t.error("names", [], "lists no sensor", "remove [structure_sensors] instead")
    config = SensorConfig(
        names=names,
        noise_k=t.number("noise_k", d.noise_k, min=0.0, max=10.0),
        resolution_k=t.number("resolution_k", d.resolution_k, min=0.0, max=10.0),
        lag_s=t.number("lag_s", d.lag_s, min=0.0, max=86400.0),
        local_k=t.number("local_k", d.local_k, min=0.0, max=20.0),
        local_timescale_s=t.number("local_timescale_s", d.local_timescale_s, min=60.0,
                                   max=864000.0),
    )
    t.finish()
    return config


def _model_file(t: Table, spec: str, base: Path) -> PointingModel:
    from controller.pointing.modelio import load_model

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
            from controller.pointing.equatorial import equatorial_term

            effect = cls.from_table(t, lambda n: equatorial_term(n, site.latitude_deg))
        else:
            effect = cls.from_table(t)
        return EffectSpec(name, {"terms_arcsec": dict(effect.values_arcsec)})
    effect = cls.from_table(t)
    return EffectSpec(name, effect.params())


def _check_clock(effects, duration_s: float, truth: Table) -> None:
    """A clock error at most the hour the simulated sky reaches beyond the campaign (the
    world computes the sky at the true time of the antenna's clock)."""
    from controller.program.campaign import EPHEMERIS_MARGIN_S

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


def _controller(t: Table, site: Site, epoch: str, duration_s: float, sources, receiver,
                mount: MountConfig, scenario_name: str, base: Path,
                camera: CameraConfig | None = None) -> ControllerConfig:
    model = _model(t, default="none", base=base, mount=mount, site=site)
    names = [s.name for s in sources]
    scan_t = t.table("scan", {})
    ds = ScanConfig()
    scan = ScanConfig(
        step_arcmin=scan_t.number("step_arcmin", ds.step_arcmin, gt=0.0),
        # the noise of an integration is the scatter of its samples: two at least
        integration_s=scan_t.number("integration_s", ds.integration_s,
                                    min=2.0 * receiver.sample_interval_s, max=3600.0),
        hpbw_arcmin=scan_t.number("hpbw_arcmin", ds.hpbw_arcmin, min=0.01, max=600.0),
        estimator=scan_t.string("estimator", ds.estimator, choices=ESTIMATORS),
        snr_min=scan_t.number("snr_min", ds.snr_min, min=0.0),
        overhead_s=scan_t.number("overhead_s", ds.overhead_s, min=0.0, max=3600.0),
        use_source_size=scan_t.boolean("use_source_size", ds.use_source_size),
    )
    samples = scan.integration_s / receiver.sample_interval_s
    if samples > MAX_SAMPLES:
        raise scan_t.error("integration_s", scan.integration_s,
                           f"holds {samples:.3g} samples of receiver.sample_interval_s = "
                           f"{receiver.sample_interval_s:g} s; at most {MAX_SAMPLES:g}",
                           "integrate less or sample less often")
    if scan.step_arcmin > 1.2 * scan.hpbw_arcmin:
        raise scan_t.error("step_arcmin", scan.step_arcmin,
                           f"the +-D points would lie outside the main beam (HPBW "
                           f"{scan.hpbw_arcmin:g}')",
                           f"use at most {1.2 * scan.hpbw_arcmin:.1f}'")
    scan_t.finish()
    sched_t = t.table("scheduler", {})
    dsch = SchedulerConfig()
    chosen = tuple(sched_t.strings("sources", list(dsch.sources)))
    for s in chosen:
        if s not in names:
            raise sched_t.error("sources", s, "unknown source", f"sources are {', '.join(names)}")
    sched = SchedulerConfig(
        policy=sched_t.string("policy", dsch.policy, choices=("spread", "round_robin")),
        elevation_min_deg=sched_t.number("elevation_min_deg", dsch.elevation_min_deg,
                                         min=0.0, max=89.0),
        elevation_max_deg=sched_t.number("elevation_max_deg", dsch.elevation_max_deg,
                                         min=1.0, max=90.0),
        min_revisit_s=sched_t.number("min_revisit_s", dsch.min_revisit_s, min=0.0),
        slew_weight=sched_t.number("slew_weight", dsch.slew_weight, min=0.0),
        window=sched_t.string("window", dsch.window, choices=("all", "day", "night")),
        sources=chosen,
        hour_angle_limit_deg=(
            sched_t.number("hour_angle_limit_deg",
                           min(-mount.az.min_deg, mount.az.max_deg) - 2.0, gt=0.0, max=180.0)
            if mount.kind == "equatorial" else None),
        declination_max_deg=sched_t.number("declination_max_deg", None, min=-90.0, max=90.0,
                                           allow_none=True),
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
    search_t = t.table("search", {})
    dse = SearchConfig()
    search = SearchConfig(
        enabled=search_t.boolean("enabled", dse.enabled),
        step_factor=search_t.number("step_factor", dse.step_factor, min=1.0, max=5.0),
        update_gain=search_t.number("update_gain", dse.update_gain, min=0.0, max=1.0),
        correction=search_t.string("correction", dse.correction, choices=("sky", "encoders")),
        max_cross_offset_beams=(search_t.number("max_cross_offset_beams", gt=0.0, max=10.0)
                                if "max_cross_offset_beams" in search_t else None),
    )
    search_t.finish()
    refraction = t.string("refraction", "weather", choices=("weather", "standard", "none"))
    fit_terms, fit_name = _fit_spec(t, mount, site)
    fit_fixed = _fit_fixed(t, fit_terms)
    method = t.string("method", "five_point", choices=("five_point", "optical"))
    if method == "optical" and camera is None:
        raise t.error("method", method, "optical pointing needs a [camera] table")
    if camera is not None and method != "optical":
        raise t.error("method", method, "a scenario with a [camera] points optically",
                      'set controller.method = "optical"')
    feed_angles = tuple(t.numbers("feed_angles_deg", []))
    if any(not -360.0 <= f <= 360.0 for f in feed_angles):
        raise t.error("feed_angles_deg", list(feed_angles), "angles must lie in -360..360 deg")
    tipping = _tipping(t.table("tipping")) if "tipping" in t else None
    sky = _sky(t.table("sky")) if "sky" in t else None
    optical = _optical(t.table("optical")) if "optical" in t else (
        OpticalConfig() if method == "optical" else None)
    gain_curve = _gain_curve(t.table("gain_curve"), names) if "gain_curve" in t else None
    # what "night" means for the campaign's night window and its night fit (E)
    night = t.number("night_sun_max_deg", NIGHT_SUN_MAX_DEG, min=-18.0, max=0.0)
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
    spec = t.string("fit_model", "")
    if not spec:
        return (), ""
    lookup = get_term
    named = NAMED_MODELS
    if mount is not None and mount.kind == "equatorial":
        from controller.pointing.equatorial import EQUATORIAL_MODELS, equatorial_term

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
    scale = UNIT_ARCSEC[t.string("units", "arcsec", choices=tuple(UNIT_ARCSEC))]
    fixed_t = t.table("fit_fixed")
    out = []
    for key in fixed_t:
        name = key.strip().upper()
        if name not in fit_terms:
            raise fixed_t.error(key, fixed_t.raw(key), "is not a term of controller.fit_model",
                                f"its terms are {' '.join(fit_terms) or '(none given)'}")
        out.append((name, fixed_t.number(key) * scale))
    fixed_t.finish()
    return tuple(out)


def _camera(t: Table) -> CameraConfig:
    d = CameraConfig()
    cam = CameraConfig(
        wavelength_um=t.number("wavelength_um", d.wavelength_um, min=0.2, max=30.0),
        noise_arcsec=t.number("noise_arcsec", d.noise_arcsec, min=0.0, max=600.0),
        field_arcmin=t.number("field_arcmin", d.field_arcmin, gt=0.0, max=600.0),
    )
    t.finish()
    return cam


def _stars(t: Table) -> tuple[SourceConfig, ...]:
    """``[stars]``: ``count`` synthetic bright stars above ``dec_min_deg`` (antsim.world.camera)."""
    count = t.integer("count", min=1, max=5000)
    dec_min = t.number("dec_min_deg", -30.0, min=-90.0, lt=90.0)
    t.finish()
    return tuple(SourceConfig(name, ra, dec, "icrs", 1.0, 0.0, "synthetic bright star")
                 for name, ra, dec in synthetic_stars(count, dec_min))


def _sky(t: Table) -> SkyConfig:
    d = SkyConfig()
    sky = SkyConfig(zenith_opacity=t.number("zenith_opacity", d.zenith_opacity, min=0.0, max=5.0),
                    t_atm_k=t.number("t_atm_k", d.t_atm_k, gt=100.0, max=350.0))
    t.finish()
    return sky


def _tipping(t: Table) -> TippingConfig:
    d = TippingConfig()
    els = tuple(t.numbers("elevations_deg", list(d.elevations_deg), min_length=3))
    if any(not 5.0 <= e <= 90.0 for e in els):
        raise t.error("elevations_deg", list(els), "elevations must lie in 5..90 deg")
    if len(set(els)) < 3:
        raise t.error("elevations_deg", list(els), "needs at least three different elevations")
    tip = TippingConfig(
        elevations_deg=els,
        azimuth_deg=t.number("azimuth_deg", d.azimuth_deg, min=0.0, lt=360.0),
        integration_s=t.number("integration_s", d.integration_s, gt=0.0, max=600.0),
        interval_s=t.number("interval_h", d.interval_s / 3600.0, gt=0.0, max=1000.0) * 3600.0,
        t_atm_k=t.number("t_atm_k", d.t_atm_k, gt=100.0, max=350.0),
    )
    t.finish()
    return tip


def _optical(t: Table) -> OpticalConfig:
    d = OpticalConfig()
    opt = OpticalConfig(exposure_s=t.number("exposure_s", d.exposure_s, gt=0.0, max=600.0),
                        overhead_s=t.number("overhead_s", d.overhead_s, min=0.0, max=3600.0))
    t.finish()
    return opt


def _gain_curve(t: Table, names: list[str]) -> GainCurveConfig:
    d = GainCurveConfig()
    sources = tuple(t.strings("sources", list(d.sources)))
    for s in sources:
        if s not in names:
            raise t.error("sources", s, "unknown source", f"sources are {', '.join(names)}")
    knots = tuple(t.numbers("knots_deg", list(d.knots_deg), min_length=2))
    if any(b <= a for a, b in pairwise(knots)):
        raise t.error("knots_deg", list(knots), "must increase")
    gc = GainCurveConfig(
        kind=t.string("kind", d.kind, choices=("elevation", "harmonics")),
        sources=sources, knots_deg=knots,
        zenith_opacity=t.number("zenith_opacity", None, min=0.0, max=5.0, allow_none=True),
        t_atm_k=t.number("t_atm_k", d.t_atm_k, gt=100.0, max=350.0),
    )
    t.finish()
    return gc
