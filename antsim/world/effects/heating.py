"""The Sun heating the structure: a heat balance per member, pointing from the geometry.

Physics (:mod:`antsim.world.heat` for the balance, :mod:`antsim.world.structure` for the
pointing per kelvin): each member absorbs ``absorptivity`` times the direct sunlight on its
projected area, once; it loses heat to the air by convection (which rises with the wind) and
by long-wave radiation; its time constant is its heat capacity over that loss. Three parts,
each a pair of members whose temperature difference bends the structure:

* the **feed legs** (a quadripod of steel tubes, wall ``leg_wall_m``): a tube of axis ``u``
  intercepts the sunlight over its silhouette, ``sqrt(1 - (s.u)^2)`` of its diameter, and
  loses heat over its whole circumference (pi times the diameter): its equilibrium excess is
  ``alpha E sqrt(1 - (s.u)^2) / (pi h)``; with the Sun behind the dish the dish shades the
  part of each leg from which its aperture stands between the leg and the Sun.
  The upper leg against the lower (with the dish at the horizon) moves the beam in
  elevation, the right against the left in cross-elevation;
* the **yoke arms** (steel box girders, plates ``yoke_plate_m`` thick, each plate cooled
  outside by the air and inside by ``inside_w_m2k``): the Sun on their front or back faces
  (normal along the horizontal direction the antenna faces) bows both arms, an elevation
  error; the Sun on one arm's outer face (normal along the elevation axis) lengthens that arm
  (its mean is a quarter of its faces), rolling the elevation axis;
* the **pedestal** (a steel cylinder, wall ``pedestal_wall_m``): its sunlit side is warmer
  by ``alpha E cos h / h`` at the Sun's azimuth, the axis leans away from it (an azimuth-axis
  tilt that follows the Sun through the day).

The legs and the yoke depend on where the antenna points, so their differences are
advanced from integration to integration (as if the antenna had pointed at the latest
direction since the previous instant, relaxing with the time constant of the moment); the
pedestal and the mean structure temperature are computed on a one-minute grid with a day of
spin-up. Wind (``antsim.world.weather``) sets the convective coefficient and so every time
constant. Thin cloud removes a random fraction of the direct sunlight, rms
``cloud_modulation`` (the report: "quite clear during most of the 24-hour observing run").

Not simulated: the sunlight the dish concentrates near its focus (the scheduler does not
point near the Sun), shadows of the dish on the yoke and the pedestal, the backup
structure's own gradient under the panels, and the diffuse sky light (it heats every face
alike). ``docs/physics.md`` gives every parameter's value, range and source.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from controller.units import RAD_PER_ARCSEC

from ..heat import (
    convective_coefficient_w_m2k,
    direct_normal_irradiance_w_m2,
    radiative_coefficient_w_m2k,
    relax_varying,
    sky_temperature_k,
)
from ..structure import STEEL_EXPANSION_PER_K, Structure
from .base import Effect, Key, PointingState
from .thermal import GRID_STEP_S, ScalarInterpolator, campaign_grid_s, interp_rows, ou_series

__all__ = ["PARTS", "ThermalEffect", "member_forcings"]

#: the pointing-dependent differences, in the order of the effect's state: feed legs upper
#: minus lower and right minus left, yoke arms' front minus back faces and right minus left
#: arm (K)
PARTS = ("legs_ul", "legs_rl", "yoke_fb", "yoke_rl")
#: the feeds legs' feet on the rim in the aperture's (up, right) coordinates: upper, lower,
#: right, left
_LEG_FEET = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]])
#: kelvin in 0 C
ZERO_C_K = 273.15


#: the feet of the legs along axis 0, broadcast against (points, ...)
_FEET_UP = _LEG_FEET[:, 0]
_FEET_RIGHT = _LEG_FEET[:, 1]


def _leg_lit(sb, su, sx, geometry: Structure):
    """Fraction of each of the four legs (axis 0) in sunlight: all of it with the Sun in
    front of the dish (``sb`` >= 0); behind it, the part whose ray to the Sun crosses the
    rim's plane outside the aperture. ``sb``, ``su``, ``sx``: the Sun's components along the
    boresight, up the aperture and to its right (arrays of one shape).

    A leg's point a fraction t of the way from its foot f (a unit vector across the
    aperture, in radii) to the focus meets the rim's plane, along the ray to the Sun, at
    f + t d, d = r s' - f, with s' = (su, sx) and r = (F - R^2/4F) / (R (-sb)) the ray's
    reach per unit of t: inside the aperture (|f + t d| < 1) for 0 < t < -2 f.d / |d|^2.
    The shaded fraction is that bound, clipped to [0, 1]."""
    sb, su, sx = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (sb, su, sx)))
    behind = sb < -1e-9
    if not behind.any():
        return np.ones((4, *sb.shape))
    radius = 0.5 * geometry.diameter_m
    rise = geometry.focal_length_m - geometry.rim_depth_m
    reach = rise / (radius * np.maximum(-sb, 1e-9))  # (used only where the Sun is behind)
    lead = (1,) * sb.ndim
    along_foot = _FEET_UP.reshape((4, *lead)) * su + _FEET_RIGHT.reshape((4, *lead)) * sx
    f_dot_d = reach * along_foot - 1.0
    d_squared = np.maximum(reach * reach * (su * su + sx * sx) - 2.0 * reach * along_foot
                           + 1.0, 1e-300)
    # -2 f.d / |d|^2 is negative where f.d > 0 (the leg's foot sees past the rim): no shade
    shaded = np.minimum(np.maximum(-2.0 * f_dot_d / d_squared, 0.0), 1.0)
    return np.where(behind, 1.0 - shaded, 1.0)


def member_forcings(absorbed_w_m2, h_out_w_m2k, h_plate_w_m2k, sun_n, sun_e, sun_u, az_rad,
                    el_rad, geometry: Structure) -> np.ndarray:
    """The equilibrium differences (K) of :data:`PARTS` for the antenna pointing at
    (``az_rad``, ``el_rad``) under the Sun (unit vector north, east, up) delivering
    ``absorbed_w_m2`` (absorptivity times the direct normal irradiance): shape (4, ...)."""
    absorbed = np.asarray(absorbed_w_m2, dtype=float)
    shape = np.broadcast_shapes(absorbed.shape, np.shape(az_rad), np.shape(el_rad))
    if not absorbed.any():  # the Sun down: no member is forced away from the others
        return np.zeros((4, *shape))
    cos_e, sin_e = np.cos(el_rad), np.sin(el_rad)
    cos_a, sin_a = np.cos(az_rad), np.sin(az_rad)
    # the Sun along the horizontal direction faced, to the right (d b / d A), along the
    # boresight b and up the aperture (d b / d E)
    ahead = sun_n * cos_a + sun_e * sin_a
    sx = sun_e * cos_a - sun_n * sin_a
    sb = ahead * cos_e + sun_u * sin_e
    su = sun_u * cos_e - ahead * sin_e
    phi = geometry.leg_angle_rad
    along, across_u, across_x = math.cos(phi) * sb, math.sin(phi) * su, math.sin(phi) * sx
    # each leg's axis: cos phi along the boresight less sin phi towards its foot (upper,
    # lower, right, left); its silhouette sqrt(1 - (s.u)^2), times the part in the Sun
    cosine = np.empty((4, *shape))
    cosine[0] = along - across_u
    cosine[1] = along + across_u
    cosine[2] = along - across_x
    cosine[3] = along + across_x
    shown = np.sqrt(np.maximum(1.0 - cosine * cosine, 0.0))
    if (sb < -1e-9).any():
        shown *= _leg_lit(sb, su, sx, geometry)
    out = np.empty((4, *shape))
    tube = absorbed / (math.pi * h_out_w_m2k)
    out[0] = tube * (shown[0] - shown[1])
    out[1] = tube * (shown[2] - shown[3])
    # the yoke's vertical faces: the horizontal direction the antenna faces, and its right
    face = absorbed / h_plate_w_m2k
    out[2] = face * ahead
    out[3] = 0.25 * face * sx
    return out


class ThermalEffect(Effect):
    """The Sun heating the structure, from a heat balance (see the module docstring)."""

    name: ClassVar[str] = "thermal"
    explanation: ClassVar[str] = (
        "the Sun heats the sides of the feed legs, the yoke and the pedestal that face it; "
        "their temperature differences bend the structure, follow the Sun and the antenna's "
        "direction with time constants of minutes to an hour, and relax after sunset"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "absorptivity": Key(0.25, "solar absorptivity of the paint (white: 0.19-0.25 new, up "
                            "to ~0.4 weathered)", min=0.0, max=1.0, unit="1",
                            source="tables of coatings' solar absorptance"),
        "emissivity": Key(0.9, "long-wave emissivity of the paint (white: 0.85-0.94)",
                          min=0.0, max=1.0, unit="1"),
        "heat_capacity_j_m3k": Key(3.6e6, "volumetric heat capacity of the steel (7850 kg/m^3 "
                                   "x 460 J/(kg K))", min=1e5, max=1e7, unit="J/(m^3 K)"),
        "expansion_per_k": Key(STEEL_EXPANSION_PER_K, "linear expansion of the steel",
                               min=0.0, max=1e-4, unit="1/K"),
        "leg_wall_m": Key(0.006, "wall thickness of the feed legs' tubes (4-8 mm)", min=1e-4,
                          max=0.1),
        "yoke_plate_m": Key(0.015, "plate thickness of the yoke arms (10-25 mm)", min=1e-4,
                            max=0.2),
        "pedestal_wall_m": Key(0.02, "wall thickness of the pedestal (12-25 mm)", min=1e-4,
                               max=0.2),
        "inside_w_m2k": Key(5.0, "heat transfer from a plate to the still air and the other "
                            "plates inside a closed box girder (3-8)", min=0.0, max=100.0,
                            unit="W/(m^2 K)"),
        "diameter_m": Key(13.7, "dish diameter", min=1.0, max=200.0,
                          source="Ghigo 1990, section I"),
        "focal_length_m": Key(5.5, "prime focal length (F/D 0.3-0.45)", min=0.5, max=100.0),
        "yoke_height_m": Key(3.0, "height of the yoke arms, azimuth bearing to elevation axis "
                             "(2-4.5)", min=0.1, max=50.0),
        "yoke_depth_m": Key(1.0, "depth of a yoke arm, front face to back face (0.6-1.5)",
                            min=0.05, max=20.0),
        "yoke_separation_m": Key(4.0, "distance between the yoke arms (3-6)", min=0.1,
                                 max=100.0),
        "pedestal_height_m": Key(5.0, "height of the pedestal (3-7)", min=0.1, max=100.0),
        "pedestal_diameter_m": Key(2.5, "diameter of the pedestal (1.8-3.5)", min=0.1,
                                   max=100.0),
        "cloud_modulation": Key(0.1, "rms fraction of the direct sunlight that passing thin "
                                "cloud removes (0: a clear sky)", min=0.0, max=1.0, unit="1",
                                source="Ghigo 1990, section IV: quite clear during most of "
                                "the run"),
        "cloud_timescale_s": Key(1800.0, "correlation time of the cloud", min=60.0),
    }

    # ------------------------------------------------------------------ set-up
    @property
    def structure(self) -> Structure:
        """The geometry and the steel of this effect's antenna."""
        p = self.p
        return Structure(diameter_m=p["diameter_m"], focal_length_m=p["focal_length_m"],
                         yoke_height_m=p["yoke_height_m"], yoke_depth_m=p["yoke_depth_m"],
                         yoke_separation_m=p["yoke_separation_m"],
                         pedestal_height_m=p["pedestal_height_m"],
                         pedestal_diameter_m=p["pedestal_diameter_m"],
                         expansion_per_k=p["expansion_per_k"])

    def coefficients(self) -> dict[str, float]:
        """Pointing per kelvin of each pair (arcsec/K, :meth:`Structure.coefficients`)."""
        return self.structure.coefficients()

    def start(self, world, rng: np.random.Generator) -> None:
        p = self.p
        step = GRID_STEP_S
        t = campaign_grid_s(world.duration_s)
        sun_el = world.sun_el_rad_periodic(t)
        sun_az = world.sun_az_rad(t)
        height = float(getattr(getattr(world.scenario, "site", None), "height_m", 0.0))
        shade = np.clip(1.0 - np.abs(ou_series(rng, t.size, step, p["cloud_timescale_s"],
                                               p["cloud_modulation"])), 0.0, 1.0)
        beam = direct_normal_irradiance_w_m2(sun_el, height) * shade
        daily_k = world.weather.daily_curve_c(t) + ZERO_C_K
        wind = world.weather.wind_m_s(t)
        h_rad = radiative_coefficient_w_m2k(p["emissivity"], daily_k)
        h_out = convective_coefficient_w_m2k(wind) + h_rad
        h_plate = h_out + p["inside_w_m2k"]
        self.structure_geometry = self.structure
        self.k = self.coefficients()
        self.t_grid = t
        cos_h = np.cos(sun_el)
        self._sun_vec = np.stack([cos_h * np.cos(sun_az), cos_h * np.sin(sun_az),
                                  np.sin(sun_el)])  # north, east, up
        self._absorbed = p["absorptivity"] * beam  # W/m^2 on a surface facing the Sun
        self._h_out = h_out
        self._h_plate = h_plate
        #: the insolation (0..1, the Sun's height and the cloud): scales the sensors' local
        #: departures (antsim.world.sensors)
        self._insolation = np.clip(np.sin(sun_el), 0.0, None) * shade
        capacity = p["heat_capacity_j_m3k"]
        self._tau_leg = capacity * p["leg_wall_m"] / h_out
        self._tau_yoke = capacity * p["yoke_plate_m"] / h_plate
        # the pedestal: its N - S and E - W differences, sunlit side warmer
        tau_ped = capacity * p["pedestal_wall_m"] / h_plate
        horizontal = self._absorbed * cos_h / h_plate
        self.pedestal_n_k = relax_varying(horizontal * np.cos(sun_az), tau_ped, step, 0.0)
        self.pedestal_e_k = relax_varying(horizontal * np.sin(sun_az), tau_ped, step, 0.0)
        # the structure's mean: the air, plus the sunlight a vertical cylinder absorbs on
        # average (1/pi of a face towards the Sun), less what its faces (half sky, half
        # ground at the air's temperature) radiate to a clear sky colder than the air
        air = world.air_temperature_c(t)
        air_k = air + ZERO_C_K
        sky_loss = 0.5 * h_rad * (air_k - sky_temperature_k(air_k))
        mean_excess = (self._absorbed * cos_h / math.pi - sky_loss) / h_plate
        self.structure_c = relax_varying(air + mean_excess, tau_ped, step, float(air[0]))
        tilt = self.k["pedestal_tilt"]
        # the warmer side expands and the pedestal bends away from it: the azimuth axis
        # tilts towards the cooler side (north when the south face is the warmer, west when
        # the east face is), in both directions alike. Tilts towards north and east (arcsec)
        self._tilt_n_arcsec = -tilt * self.pedestal_n_k
        self._tilt_e_arcsec = -tilt * self.pedestal_e_k
        #: (time -> forcings, differences and time constants of the pointing-dependent
        #: parts) of every instant their state advanced to, kept only when structure sensors
        #: read it (antsim.world.sensors)
        self.parts_log: dict[float, tuple] | None = None
        self._parts = None
        self._parts_t = None
        self._block = None
        self._now = None

    # ------------------------------------------------------------------ the series
    def _series(self):
        return (*self._sun_vec, self._absorbed, self._h_out, self._h_plate, self._tau_leg,
                self._tau_yoke, self._tilt_n_arcsec, self._tilt_e_arcsec)

    def series_at(self, t_s) -> list:
        """Every series at time(s) ``t_s``: the Sun (3), absorbed flux, h outside, h of a
        plate, the legs' and yoke's time constants, the tilts (arcsec). Plain floats for one
        time without a member axis; else arrays (K,), or (K, members) for stacked series."""
        if np.ndim(t_s) == 0 and all(np.ndim(v) == 1 for v in self._series()):
            if self._now is None:
                self._now = ScalarInterpolator(self.t_grid, self._series())
            return self._now(float(t_s))
        t = np.asarray(t_s, dtype=float)
        out = []
        for v in self._series():
            if np.ndim(v) == 1:
                out.append(np.interp(t, self.t_grid, v))
            else:  # (members, n): (K, members) at times (K, 1)
                out.append(interp_rows(t.ravel(), self.t_grid, v).T.reshape(
                    *t.shape[:-1], -1) if t.ndim > 1 else interp_rows(t, self.t_grid, v))
        return out

    def forcings_k(self, t_s, az_rad, el_rad) -> np.ndarray:
        """The equilibrium differences of :data:`PARTS` (K) at time(s) ``t_s`` for the
        antenna pointing at (``az_rad``, ``el_rad``): shape (4, ...)."""
        sun_n, sun_e, sun_u, absorbed, h_out, h_plate = self.series_at(t_s)[:6]
        return member_forcings(absorbed, h_out, h_plate, sun_n, sun_e, sun_u, az_rad, el_rad,
                               self.structure_geometry)

    # ------------------------------------------------------------------ the state
    def _advance(self, times: list[float], forcing: np.ndarray, tau_leg: list[float],
                 tau_yoke: list[float]) -> np.ndarray:
        """The differences at each of ``times`` (in order), each relaxing from the previous
        instant's towards that instant's ``forcing`` (4, K[, members]) with that instant's
        time constants (s, K each); returns (4, K[, members]) and leaves the state at the
        last instant."""
        if self._parts is None:  # no past: the first instant starts at its forcing
            self._parts, self._parts_t = forcing[:, 0].copy(), times[0]
        out = np.empty_like(forcing)
        parts, last = self._parts, self._parts_t
        if forcing.ndim == 2:  # one antenna: plain floats
            values = [float(v) for v in parts]
            for k, (t_k, row) in enumerate(zip(times, forcing.T.tolist(), strict=True)):
                dt = t_k - last
                if dt > 0.0:  # time went on
                    d_leg = math.exp(-dt / tau_leg[k])
                    d_yoke = math.exp(-dt / tau_yoke[k])
                    values = [row[0] + (values[0] - row[0]) * d_leg,
                              row[1] + (values[1] - row[1]) * d_leg,
                              row[2] + (values[2] - row[2]) * d_yoke,
                              row[3] + (values[3] - row[3]) * d_yoke]
                    last = t_k
                out[:, k] = values
            parts = np.array(values)
        else:  # a member axis: rows (4, members)
            for k, t_k in enumerate(times):
                dt = t_k - last
                if dt > 0.0:
                    taus = np.array([tau_leg[k], tau_leg[k], tau_yoke[k], tau_yoke[k]])
                    decay = np.exp(-dt / taus).reshape(4, *[1] * (forcing.ndim - 2))
                    parts = forcing[:, k] + (parts - forcing[:, k]) * decay
                    last = t_k
                out[:, k] = parts
        self._parts, self._parts_t = parts, last
        return out

    def _block_parts(self, t, az_rad, el_rad, series=None) -> tuple[np.ndarray, list]:
        """The differences (4, K[, members]) at times ``t`` (K,) or (K, 1), pointing at
        (az, el) (K,) or (K, members) at each, advanced from the state before them; and the
        series at those times (:meth:`series_at`, or ``series`` when the caller has them)."""
        if series is None:
            series = self.series_at(t)
        sun_n, sun_e, sun_u, absorbed, h_out, h_plate, tau_leg, tau_yoke = series[:8]
        forcing = member_forcings(absorbed, h_out, h_plate, sun_n, sun_e, sun_u, az_rad,
                                  el_rad, self.structure_geometry)
        times = np.asarray(t, dtype=float).ravel().tolist()
        n = len(times)
        # the time constants follow the wind and the air: the same for every member
        tau_leg = np.asarray(tau_leg, dtype=float).reshape(n).tolist()
        tau_yoke = np.asarray(tau_yoke, dtype=float).reshape(n).tolist()
        parts = self._advance(times, forcing, tau_leg, tau_yoke)
        if self.parts_log is not None and forcing.ndim == 2:  # a World, not members
            for k, t_k in enumerate(times):
                self.parts_log[float(t_k)] = (tuple(forcing[:, k].tolist()),
                                              tuple(parts[:, k].tolist()),
                                              tau_leg[k], tau_yoke[k])
        return parts, series

    # ------------------------------------------------------------------ the errors
    def _errors(self, parts, tilt_n, tilt_e, az_rad, el_rad):
        """(d_az, d_el) in rad from the differences (4, ...) and the azimuth axis' tilts
        towards north and east (arcsec). An axis tilted north by i (its pole north of the
        zenith) tips the frame's northern horizon down: indicated minus true dE = i cos A,
        dA cos E = i sin A sin E; tilted east, dE = i sin A, dA cos E = -i cos A sin E."""
        k = self.k
        sin_e, cos_e = np.sin(el_rad), np.cos(el_rad)
        sin_a, cos_a = np.sin(az_rad), np.cos(az_rad)
        el = k["legs_el"] * parts[0] + k["yoke_bow"] * parts[2] \
            + (tilt_n * cos_a + tilt_e * sin_a)
        xel = k["legs_xel"] * parts[1] + k["yoke_roll"] * parts[3] * sin_e
        d_az = xel / cos_e + (tilt_n * sin_a - tilt_e * cos_a) * sin_e / cos_e
        return d_az * RAD_PER_ARCSEC, el * RAD_PER_ARCSEC

    def pointing_error(self, state: PointingState) -> tuple[float, float]:
        """The error at one instant (a World's single integrations, a camera); with a member
        axis, ``state``'s directions (members,) and an error per member."""
        t = np.array([float(np.asarray(state.t_s).flat[0])])
        az = np.asarray(state.az_rad, dtype=float)[None, ...]
        el = np.asarray(state.el_rad, dtype=float)[None, ...]
        if az.ndim > 1 or el.ndim > 1:
            t = t[:, None]
        parts, series = self._block_parts(t, az, el)
        d_az, d_el = self._errors(parts, series[8], series[9], az, el)
        if np.ndim(state.az_rad) == 0 and np.ndim(state.el_rad) == 0:
            return float(np.asarray(d_az).flat[0]), float(np.asarray(d_el).flat[0])
        return np.asarray(d_az)[0], np.asarray(d_el)[0]

    def block_error(self, state: PointingState) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`pointing_error` at K instants (arrays (K,)), see
        :meth:`Effect.block_error`: the differences advance over the K times from where they
        stood before them, forced from the directions of the latest call, so the fixed point
        converges to differences forced from where the beam truly pointed."""
        t = state.t_s  # (K,), or (K, 1) with a member axis
        key = (t.size, float(t.flat[0]), float(t.flat[-1]))
        if self._block is None or self._block[0] != key:  # the series once per block
            self._block = (key, (self._parts, self._parts_t), self.series_at(t))
        self._parts, self._parts_t = self._block[1]
        parts, series = self._block_parts(t, state.az_rad, state.el_rad, self._block[2])
        return self._errors(parts, series[8], series[9], state.az_rad, state.el_rad)

    def equilibrium_errors_arcsec(self, t_s, az_rad, el_rad) -> tuple[np.ndarray, np.ndarray]:
        """(xel, el) error (arcsec) with the legs and the yoke at their equilibrium for
        pointing at (az, el) at time(s) ``t_s`` (no state involved; tests and reports)."""
        parts = self.forcings_k(t_s, az_rad, el_rad)
        series = self.series_at(t_s)
        d_az, d_el = self._errors(parts, series[8], series[9], az_rad, el_rad)
        return (np.asarray(d_az) * np.cos(el_rad) / RAD_PER_ARCSEC,
                np.asarray(d_el) / RAD_PER_ARCSEC)
