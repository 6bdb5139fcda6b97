"""The scenario file's keys, table by table: the one declaration :mod:`antsim.scenario` reads
them by and ``docs/scenarios.md`` lists them from.

Each :class:`~antsim.schema.keys.Section` is bound to the world's or the controller's settings
dataclass it fills, whose field defaults are the keys' defaults (the scenario's own
dataclass, :class:`antsim.scenario.Scenario`, sits above this module and is named). The
effects of ``[[truth.effects]]`` declare their parameters beside their physics (``PARAMS``
of each class in :mod:`antsim.world.effects`); :func:`effect_sections` lists them here.
"""

from __future__ import annotations

from controller.astro.site import Site
from controller.pointing.modelio import MAX_VALUE_ARCSEC
from controller.program.campaign import EPHEMERIS_MARGIN_S
from controller.program.config import (
    ControllerConfig,
    OpticalConfig,
    SchedulerConfig,
    SearchConfig,
)
from controller.scans.config import GainCurveConfig, ScanConfig, SkyConfig, TippingConfig
from controller.scans.gaincurve import HARMONIC_NAMES

from ..world.atmosphere import AtmosphereConfig
from ..world.beam import BeamConfig
from ..world.camera import CameraConfig
from ..world.effects import EFFECTS
from ..world.mount import AxisConfig, MountConfig
from ..world.receiver import ChannelConfig, ReceiverConfig
from ..world.sensors import SensorConfig
from ..world.sky import SourceConfig
from ..world.weather import WeatherConfig
from .keys import REQUIRED, Key, Section

__all__ = ["ESTIMATORS", "MAX_DURATION_H", "MAX_SAMPLES", "MAX_TIMESCALE_S", "SCENARIO",
           "UNIT_ARCSEC",
           "effect_sections", "section"]

#: a table's ``units`` -> arcsec per unit
UNIT_ARCSEC = {"arcsec": 1.0, "arcmin": 60.0, "deg": 3600.0}
#: the reductions of a five-point scan (controller.scans.reduction)
ESTIMATORS = ("clark", "lsq")
#: longest correlation time of a random process (s): about 3 years; beyond it a process is a
#: constant, and its one-step correlation rounds to 1 (a division by zero)
MAX_TIMESCALE_S = 1e8
#: most receiver samples in one integration (each is a few numbers per channel in memory)
MAX_SAMPLES = 100_000
#: the longest campaign (h): 364 days. The world computes the Sun from a day before the start
#: (the structure's heating needs a day of spin-up) to an hour after the end, and an
#: ephemeris spans at most 366 days (controller.astro.ephemeris)
MAX_DURATION_H = 364.0 * 24.0
MAX_DURATION_WHY = ("the simulated Sun runs from a day before the start to an hour after the "
                    "end, within its ephemeris's 366 days")


def _units(field: str | None = None) -> Key:
    return Key("arcsec", "unit of the values in ``terms`` and ``fit_fixed``", kind="string",
               choices=tuple(UNIT_ARCSEC), field=field)


def _terms(doc: str, field: str | None = None) -> Key:
    return Key({}, doc, kind="terms", min=-MAX_VALUE_ARCSEC, max=MAX_VALUE_ARCSEC,
               unit="arcsec", field=field,
               note="given in the table's ``units``; the bound (half a turn) is a model "
                    "file's")


def _model(doc: str) -> Key:
    return Key("none", doc, kind="string", field=None,
               note="a named model (none, ghigo10, tpoint8, ...; crane11 on an equatorial "
                    "mount) or a .mod/.dat/.json model file, relative to the scenario")


ROOT = Section("", "The scenario: its name, its seed and its tables.", {
    "name": Key(REQUIRED, "the scenario's name, written into every output", kind="name"),
    "description": Key("", "one line: what the scenario is", kind="line"),
    "seed": Key(1, "the run's random seed (same scenario and seed, same bytes)",
                kind="integer", min=0),
    "site": Key(REQUIRED, "where the antenna stands", kind="table"),
    "campaign": Key(REQUIRED, "when it observes", kind="table", field=None),
    "mount": Key({}, "the mount and its axes", kind="table"),
    "beam": Key({}, "the antenna's beam and gain", kind="table"),
    "receiver": Key({}, "the receiver and its channels", kind="table"),
    "atmosphere": Key({}, "the atmosphere's opacity and emission", kind="table"),
    "weather": Key({}, "air temperature, pressure, humidity and wind", kind="table"),
    "sources": Key([], "the pointing sources, a table each (at least one source or "
                   "[stars])", kind="tables"),
    "stars": Key(None, "synthetic bright stars added to the sources (optical pointing)",
                 kind="table", field=None),
    "camera": Key(None, "a TV camera (optical pointing)", kind="table"),
    "truth": Key({}, "the injected truth: a pointing model and physical effects",
                 kind="table", field=None),
    "structure_sensors": Key(None, "structure temperature sensors the controller reads "
                             "(none on the 1990 antenna)", kind="table"),
    "controller": Key({}, "the control program's own settings", kind="table"),
}, settings="Scenario", derived={
    "path": "the scenario file's path",
    "text": "the scenario file's text",
    "epoch_utc": "campaign.start_utc",
    "duration_s": "campaign.duration_h",
    "truth_model": "truth.model and truth.terms",
    "effects": "truth.effects",
})

SITE = Section("site", "Where the antenna stands (WGS84).", {
    "latitude_deg": Key(doc="geodetic latitude, North positive", min=-90.0, max=90.0),
    "longitude_deg": Key(doc="longitude, East positive", min=-180.0, max=360.0),
    "height_m": Key(doc="height above the ellipsoid", min=-500.0, max=9000.0),
    "name": Key(doc="the antenna's name, for reports", kind="line"),
}, settings=Site, source="docs/assumptions.md, The antenna and its site")

CAMPAIGN = Section("campaign", "When the campaign observes.", {
    "start_utc": Key(REQUIRED, "the campaign's start, e.g. 1990-02-08T17:00:00", kind="time",
                     field=None, note="UTC as ERFA knows it: from 1960 to a few years after "
                     "its leap-second table (start and end); not a leap second"),
    "duration_h": Key(REQUIRED, "the campaign's length", gt=0.0, max=MAX_DURATION_H,
                      field=None, why=MAX_DURATION_WHY,
                      note="at least one observation (a slew, the scan and its overhead)"),
})


def _axis(path: str, what: str, defaults: AxisConfig, limits_required: bool = False,
          limits_note: str = "") -> Section:
    limit = {"default": REQUIRED} if limits_required else {}
    return Section(path, f"The {what} axis.", {
        "speed_deg_s": Key(doc=f"top speed of the {what} axis", gt=0.0, max=30.0,
                           note=f"crossing the axis range takes at most "
                                f"{EPHEMERIS_MARGIN_S:g} s"),
        "accel_deg_s2": Key(doc=f"acceleration of the {what} axis", gt=0.0, max=30.0),
        "min_deg": Key(doc=f"lower limit of the {what} axis", note=limits_note, **limit),
        "max_deg": Key(doc=f"upper limit of the {what} axis", note="above min_deg", **limit),
    }, settings=AxisConfig, defaults=defaults,
        source="docs/assumptions.md, The antenna and its site")


MOUNT = Section("mount", "The mount: its kind and axes, settling, cable wrap and feed.", {
    "kind": Key(doc="altaz (azimuth, elevation) or equatorial (hour angle, declination)",
                kind="string", choices=("altaz", "equatorial"),
                source="docs/telescopes.md"),
    "az": Key({}, "the azimuth axis (altaz)", kind="table"),
    "el": Key({}, "the elevation axis (altaz)", kind="table"),
    "ha": Key(None, "the hour-angle axis (equatorial; required there)", kind="table",
              field="az"),
    "dec": Key(None, "the declination axis (equatorial; required there)", kind="table",
               field="el"),
    "settle_s": Key(doc="settling time after a slew", min=0.0, max=600.0,
                    source="docs/assumptions.md (GBT: \"seconds\")"),
    "wrap_margin_s": Key(doc="how far ahead of a slew's arrival the mount plans its cable "
                         "wrap", min=0.0, max=EPHEMERIS_MARGIN_S,
                         why="the mount plans its cable wrap at most that far ahead of a "
                             "slew's arrival"),
    "feed_speed_deg_s": Key(doc="rotation speed of a turnable feed box", min=0.2, max=90.0,
                            note="the lower bound turns the feed a full 720 deg within the "
                                 "hour the sky is computed beyond the campaign"),
}, settings=MountConfig)

_DEFAULT_MOUNT = MountConfig()
MOUNT_AZ = _axis("mount.az", "azimuth", _DEFAULT_MOUNT.az,
                 limits_note="the range spans at least 360 deg")
MOUNT_EL = _axis("mount.el", "elevation", _DEFAULT_MOUNT.el,
                 limits_note="min_deg within 0..90, max_deg at most 90")
# an equatorial mount's axes take the alt-az axes' speeds by default (their limits are its own)
MOUNT_HA = _axis("mount.ha", "hour-angle", _DEFAULT_MOUNT.az, limits_required=True,
                 limits_note="min_deg < 0 < max_deg, within -180..180")
MOUNT_DEC = _axis("mount.dec", "declination", _DEFAULT_MOUNT.el, limits_required=True,
                  limits_note="within -90..90")

BEAM = Section("beam", "The beam and the aperture's gain.", {
    "hpbw_arcmin": Key(doc="half-power beam width", min=0.01, max=600.0,
                       source="Ghigo 1990 (11' at X-band)",
                       note="0.01' (0.6\"): narrower than any radio telescope's beam"),
    "efficiency_el_deg": Key(doc="elevations of the efficiency curve's knots",
                             kind="numbers", min_length=1, note="increasing",
                             source="Ghigo 1990, section V"),
    "efficiency": Key(doc="relative efficiency at each knot (flat beyond the last)",
                      kind="numbers", min_length=1, gt=0.0, max=1.5, unit="1",
                      note="one value per efficiency_el_deg",
                      source="Ghigo 1990, section V"),
    "gain_k_per_jy": Key(doc="aperture gain at the top of the efficiency curve, one "
                         "polarization", gt=0.0, max=100.0, source="docs/assumptions.md"),
    "gain_harmonics": Key(None, "a gain curve in spherical harmonics of hour angle and "
                          "declination, replacing the elevation curve", kind="table",
                          source="Crane 1981, section I"),
}, settings=BeamConfig, derived={"extra_efficiency": "not a scenario setting (none)"})

BEAM_GAIN_HARMONICS = Section(
    "beam.gain_harmonics", "Relative gain = Y00 + Y10 + Y11e + Y11o terms (hour angle, "
    "declination).", {n: Key(0.0, f"coefficient of {n}", min=-2.0, max=2.0, unit="1")
                      for n in HARMONIC_NAMES}, source="Crane 1981, section I")

RECEIVER = Section("receiver", "The receiver: its channels, band and gain stability.", {
    "channels": Key(doc="the polarization channels, a table each", kind="tables"),
    "frequency_ghz": Key(doc="observing frequency", gt=0.0, max=1000.0),
    "radiometer_noise": Key(True, "false: leave the radiometer noise out (closure tests)",
                            kind="boolean", field=None),
    "bandwidth_mhz": Key(doc="bandwidth (the radiometer noise)", gt=0.0,
                         note="at most 2000 x frequency_ghz; not with radiometer_noise = "
                              "false", source="docs/assumptions.md"),
    "sample_interval_s": Key(doc="time between the receiver's samples", min=0.01, max=60.0,
                             note="0.01 s keeps an hour-long integration's arrays small"),
    "gain_fluctuation": Key(doc="rms relative gain fluctuation dG/G", min=0.0, max=0.1,
                            unit="1"),
    "gain_timescale_s": Key(doc="correlation time of the gain fluctuation", gt=0.0,
                            max=MAX_TIMESCALE_S),
}, settings=ReceiverConfig)

CHANNEL = Section("receiver.channels[]", "One polarization channel.", {
    "name": Key(doc="the channel's name (XR, XL, ...), unique in the receiver (upper and "
                "lower case alike)", kind="name",
                note="not AVG: the recordings' name of the channels' average"),
    "tsys_k": Key(doc="system temperature", gt=0.0, max=1e5, source="docs/assumptions.md"),
    "gain_fluctuation": Key(doc="this channel's dG/G (default: the receiver's)", min=0.0,
                            max=0.1, unit="1"),
    "gain_k_per_jy": Key(doc="this channel's peak gain, a feed of its own (default: the "
                         "beam's)", gt=0.0, max=100.0, source="Crane 1981, Table 5"),
}, settings=ChannelConfig)

ATMOSPHERE = Section("atmosphere", "The atmosphere's opacity and emission.", {
    "zenith_opacity": Key(doc="zenith opacity at the observing frequency", min=0.0, max=5.0,
                          unit="1", source="docs/assumptions.md"),
    "temperature_k": Key(doc="mean radiating temperature", gt=0.0, max=400.0),
}, settings=AtmosphereConfig)

WEATHER = Section("weather", "Air temperature, pressure, humidity and wind.", {
    "air_min_c": Key(doc="daily minimum air temperature", min=-90.0, max=60.0),
    "air_max_c": Key(doc="daily maximum air temperature", min=-90.0, max=60.0,
                     note="at least air_min_c"),
    "min_local_h": Key(doc="local mean solar time of the minimum", min=0.0, lt=24.0),
    "max_local_h": Key(doc="local mean solar time of the maximum", min=0.0, lt=24.0,
                       note="differs from min_local_h"),
    "wander_rms_c": Key(doc="rms of the random wander about the daily curve", min=0.0,
                        max=20.0),
    "wander_timescale_s": Key(doc="correlation time of the wander", gt=0.0,
                              max=MAX_TIMESCALE_S),
    "pressure_hpa": Key(doc="air pressure", min=100.0, max=1100.0),
    "relative_humidity": Key(doc="relative humidity", min=0.0, max=1.0, unit="1"),
    "wind_speed_m_s": Key(doc="wind speed at the coolest hour", min=0.0, max=60.0),
    "wind_day_m_s": Key(doc="wind speed at the warmest hour (default: constant wind)",
                        min=0.0, max=60.0),
}, settings=WeatherConfig)

SOURCE = Section("sources[]", "A pointing source: give ra or ra_deg, dec or dec_deg.", {
    "name": Key(doc="the source's name, unique in the scenario (upper and lower case "
                "alike)", kind="name"),
    "ra": Key(REQUIRED, "right ascension, e.g. 03h16m29.6s (or ra_deg)", kind="angle",
              field="ra_deg", unit="deg", min=0.0, max=360.0),
    "ra_deg": Key(REQUIRED, "right ascension (or ra)", min=0.0, max=360.0),
    "dec": Key(REQUIRED, "declination, e.g. +41d19m52s (or dec_deg)", kind="angle",
               field="dec_deg", unit="deg", min=-90.0, max=90.0),
    "dec_deg": Key(REQUIRED, "declination (or dec)", min=-90.0, max=90.0),
    "frame": Key(doc="the position's frame (fk4: B1950, as the 1990 report's Table 1)",
                 kind="string", choices=("fk4", "fk5", "icrs")),
    "flux_jy": Key(REQUIRED, "flux density at the observing frequency", gt=0.0, max=1e7),
    "size_arcmin": Key(doc="FWHM of a Gaussian of equal second moment (0: point-like)",
                       min=0.0, max=600.0),
    "note": Key(doc="a note for reports", kind="line"),
}, settings=SourceConfig)

STARS = Section("stars", "Synthetic bright stars added to the sources (optical pointing).", {
    "count": Key(REQUIRED, "how many", kind="integer", min=1, max=5000),
    "dec_min_deg": Key(-30.0, "the southernmost declination", min=-90.0, lt=90.0),
})

CAMERA = Section("camera", "A TV camera on the dish, for optical pointing.", {
    "wavelength_um": Key(doc="observing wavelength (optical refraction)", min=0.2, max=30.0),
    "noise_arcsec": Key(doc="centroid noise per axis per exposure", min=0.0, max=600.0),
    "field_arcmin": Key(doc="field of view across", gt=0.0, max=600.0),
}, settings=CameraConfig)

TRUTH = Section("truth", "The injected truth: a pointing model and physical effects.", {
    "model": _model("the true pointing model's terms (its values are zero unless terms "
                    "gives them)"),
    "units": _units(),
    "terms": _terms("the true value of each term of model, by name"),
    "effects": Key([], "physical effects, a table each (below)", kind="tables", field=None),
}, source="Ghigo 1990, section II (W1..W10); TPOINT's terms")

STRUCTURE_SENSORS = Section(
    "structure_sensors", "Structure temperature sensors the controller reads during each "
    "half of a cross scan.", {
        "names": Key(doc="which sensors (antsim diagnose --list names them)", kind="strings",
                     note="each a known sensor, once"),
        "noise_k": Key(doc="rms noise of a reading", min=0.0, max=10.0),
        "resolution_k": Key(doc="the readings' resolution", min=0.0, max=10.0),
        "lag_s": Key(doc="the sensors' response time (first order)", min=0.0, max=86400.0),
        "local_k": Key(doc="how far a sensor's member departs from its part's mean in full "
                       "sun", min=0.0, max=20.0),
        "local_timescale_s": Key(doc="correlation time of that departure", min=60.0,
                                 max=864000.0),
    }, settings=SensorConfig, derived={"notes": "not a scenario setting (none)"},
    source="docs/assumptions.md")

CONTROLLER = Section("controller", "The control program: the model it points with, what it "
                     "fits, how it scans and schedules.", {
    "model": _model("the pointing model in use (its values are zero unless terms gives "
                    "them)"),
    "units": _units(),
    "terms": _terms("the value of each term of model, by name"),
    "fit_model": Key("", "the terms fitted to the campaign: a named model or a "
                     "comma-separated list (default: those of the model in use, or "
                     "TPOINT's eight)", kind="string", field=None),
    "fit_fixed": Key({}, "terms of fit_model held at a value instead of fitted", kind="terms",
                     min=-MAX_VALUE_ARCSEC, max=MAX_VALUE_ARCSEC, unit="arcsec",
                     source="Fomalont 1973 (refraction held at 1'.1)",
                     note="given in the table's ``units``"),
    "refraction": Key(doc="the refraction the controller corrects: from its weather "
                      "sensors, a standard atmosphere, or none", kind="string",
                      choices=("weather", "standard", "none")),
    "method": Key(doc="how offsets are measured: five-point cross scans or a TV camera on "
                  "stars", kind="string", choices=("five_point", "optical"),
                  note="optical needs [camera]; a [camera] needs optical"),
    "feed_angles_deg": Key(doc="feed angles to cycle through, one per scan (empty: no feed "
                           "command)", kind="numbers", min=-360.0, max=360.0,
                           element="angles"),
    "night_sun_max_deg": Key(doc="the Sun's elevation below which it is night (the night "
                             "window and fit E)", min=-18.0, max=0.0,
                             source="docs/assumptions.md, Day and night"),
    "scan": Key({}, "the five-point cross scan", kind="table"),
    "scheduler": Key({}, "which source next", kind="table"),
    "search": Key({}, "how a missed source is found", kind="table"),
    "tipping": Key(None, "tipping scans (measure the zenith opacity)", kind="table"),
    "sky": Key(None, "the a-priori sky subtracted from every integration", kind="table"),
    "optical": Key(None, "optical pointing's exposures", kind="table"),
    "gain_curve": Key(None, "the gain curve fitted to the scans' amplitudes", kind="table"),
}, settings=ControllerConfig, derived={
    "site_latitude_deg": "site.latitude_deg",
    "site_longitude_deg": "site.longitude_deg",
    "site_height_m": "site.height_m",
    "site_name": "site.name",
    "epoch_utc": "campaign.start_utc",
    "duration_s": "campaign.duration_h",
    "sources": "sources[] (the observer's catalogue: name, position, flux, size)",
    "frequency_ghz": "receiver.frequency_ghz (the camera's for optical pointing)",
    "scenario_name": "name",
    "model": "controller.model, controller.units and controller.terms",
    "fit_terms": "controller.fit_model",
    "fit_model_name": "controller.fit_model",
    "fit_fixed": "controller.fit_fixed",
    "mount": "mount.kind",
    "structure_sensors": "structure_sensors.names",
    "structure_lag_s": "structure_sensors.lag_s",
})

SCAN = Section("controller.scan", "The five-point cross scan: offsets of -4, -1, 0, +1, +4 "
               "steps in each axis.", {
    "step_arcmin": Key(doc="the step D between the points", gt=0.0,
                       note="within 0.01..1.2 x hpbw_arcmin (a smaller step changes the "
                            "power by less than 3e-4; a larger one leaves the main beam); "
                            "the -4D point at the lowest scheduled elevation above the "
                            "mount's limit"),
    "integration_s": Key(doc="integration at each point", gt=0.0, max=3600.0,
                         note=f"two receiver samples at least, {MAX_SAMPLES:,} at most"),
    "hpbw_arcmin": Key(doc="the beam width the reduction assumes", min=0.01, max=600.0),
    "estimator": Key(doc="the reduction: Clark's method (1990 report) or least squares",
                     kind="string", choices=ESTIMATORS, source="Ghigo 1990, section VI"),
    "snr_min": Key(doc="smallest signal-to-noise ratio of a detection", min=0.0, unit="1"),
    "overhead_s": Key(doc="time per scan outside the integrations (noise cal, logging)",
                      min=0.0, max=3600.0, source="docs/assumptions.md"),
    "use_source_size": Key(doc="reduce a source of catalogued size with the width it "
                           "appears with, not the beam's", kind="boolean",
                           source="docs/assumptions.md, Reduction"),
}, settings=ScanConfig, derived={"offsets_n": "not a scenario setting: -4, -1, 0, 1, 4"})

SCHEDULER = Section("controller.scheduler", "Which source next.", {
    "policy": Key(doc="spread over the sky, or round robin", kind="string",
                  choices=("spread", "round_robin")),
    "elevation_min_deg": Key(doc="lowest elevation observed", min=0.0, max=89.0),
    "elevation_max_deg": Key(doc="highest elevation observed", min=1.0, max=90.0,
                             note="above elevation_min_deg"),
    "min_revisit_s": Key(doc="no source again within this time", min=0.0),
    "slew_weight": Key(doc="weight of the slew time (per minute) against the sky coverage "
                       "gained", min=0.0, unit="1/min"),
    "window": Key(doc="observe always, by day (Sun above 0 deg) or by night (Sun below "
                  "night_sun_max_deg)", kind="string", choices=("all", "day", "night"),
                  source="docs/assumptions.md, Day and night"),
    "sources": Key(doc="observe only these sources (empty: all)", kind="strings",
                   note="each a source of the scenario"),
    "hour_angle_limit_deg": Key(None, "equatorial mounts: observe within +-this hour angle "
                                "(default: the hour-angle axis's limits less 2 deg)",
                                gt=0.0, max=180.0),
    "declination_max_deg": Key(doc="the program cannot point above this declination "
                               "(default: no limit)", min=-90.0, max=90.0,
                               source="Crane 1981, section II"),
}, settings=SchedulerConfig)

SEARCH = Section("controller.search", "How the controller finds a source it misses.", {
    "enabled": Key(doc="search for a missed source with a wider cross", kind="boolean"),
    "step_factor": Key(doc="the search's step over the scan's", min=1.0, max=5.0, unit="1"),
    "update_gain": Key(doc="smoothing of the running correction (0: none, 1: the last scan "
                       "only)", min=0.0, max=1.0, unit="1"),
    "correction": Key(doc="the running correction: an offset on the sky, or of the two "
                      "encoders", kind="string", choices=("sky", "encoders")),
    "max_cross_offset_beams": Key(doc="adopt a search's offset in one axis only where the "
                                  "other axis's is within this many beams (default: "
                                  "always)", gt=0.0, max=10.0, unit="beams"),
}, settings=SearchConfig)

TIPPING = Section("controller.tipping", "Tipping scans: the sky's brightness at several "
                  "elevations, one set every interval_h from the start.", {
    "elevations_deg": Key(doc="the elevations of a tipping scan", kind="numbers",
                          min_length=3, min=5.0, max=90.0, element="elevations",
                          note="three different elevations at least"),
    "azimuth_deg": Key(doc="preferred azimuth of the blank sky (moved if a source is near)",
                       min=0.0, lt=360.0),
    "integration_s": Key(doc="integration at each elevation", gt=0.0, max=600.0),
    "interval_h": Key(4.0, "time between tipping scans", gt=0.0, max=1000.0,
                      field="interval_s", scale=3600.0),
    "t_atm_k": Key(doc="the observer's assumed mean radiating temperature", gt=100.0,
                   max=350.0),
}, settings=TippingConfig, source="Crane 1981, section IV")

SKY = Section("controller.sky", "The observer's a-priori sky, subtracted from every "
              "integration until a tipping scan measures the opacity.", {
    "zenith_opacity": Key(doc="a-priori zenith opacity", min=0.0, max=5.0, unit="1"),
    "t_atm_k": Key(doc="a-priori mean radiating temperature", gt=100.0, max=350.0),
}, settings=SkyConfig, source="docs/assumptions.md, Reduction")

OPTICAL = Section("controller.optical", "Optical pointing: exposure and overhead per star.", {
    "exposure_s": Key(doc="exposure per star", gt=0.0, max=600.0),
    "overhead_s": Key(doc="time per star outside the exposure", min=0.0, max=3600.0),
}, settings=OpticalConfig)

GAIN_CURVE = Section("controller.gain_curve", "The gain curve fitted to the scans' "
                     "amplitudes.", {
    "kind": Key(doc="relative gain against elevation, or spherical harmonics of hour angle "
                "and declination", kind="string", choices=("elevation", "harmonics"),
                source="Ghigo 1990, section V; Crane 1981, section I"),
    "sources": Key(doc="the calibrators (empty: every source with a flux)", kind="strings",
                   note="each a source of the scenario"),
    "knots_deg": Key(doc="the elevation curve's knots", kind="numbers", min_length=2,
                     note="increasing"),
    "zenith_opacity": Key(doc="the opacity correcting the amplitudes where no tipping "
                          "measured it (default: from the scans' off-source points)",
                          min=0.0, max=5.0, unit="1"),
    "t_atm_k": Key(doc="the assumed mean radiating temperature", gt=100.0, max=350.0),
}, settings=GainCurveConfig)


def effect_sections() -> tuple[Section, ...]:
    """A section per effect of :data:`~antsim.world.effects.EFFECTS`, its parameters with
    the bounds the scenario reads them with (:meth:`Effect.keys`)."""
    out = []
    for name, cls in sorted(EFFECTS.items()):
        keys = {"effect": Key(REQUIRED, "the effect's name", kind="string", choices=(name,))}
        keys.update(cls.keys())
        doc = (cls.explanation or "").strip()
        if name == "terms":
            keys["TERM"] = cls.TERM
        out.append(Section(f"truth.effects[] (effect = \"{name}\")",
                           doc[:1].upper() + doc[1:] + ".", keys))
    return tuple(out)


#: every table of a scenario, in the order of the reference page
SCENARIO: tuple[Section, ...] = (
    ROOT, SITE, CAMPAIGN, MOUNT, MOUNT_AZ, MOUNT_EL, MOUNT_HA, MOUNT_DEC, BEAM,
    BEAM_GAIN_HARMONICS, RECEIVER, CHANNEL, ATMOSPHERE, WEATHER, SOURCE, STARS, CAMERA,
    TRUTH, *effect_sections(), STRUCTURE_SENSORS, CONTROLLER, SCAN, SCHEDULER, SEARCH,
    TIPPING, SKY, OPTICAL, GAIN_CURVE,
)


def section(path: str) -> Section:
    """The scenario table at ``path`` (``controller.scan``, ``sources[]``)."""
    return next(s for s in SCENARIO if s.path == path)
