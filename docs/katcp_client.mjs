#!/usr/bin/env node
// A minimal antenna control program in another language than the simulation's: it drives
// `antsim serve` over KATCP (docs/katcp.md), as a user's control software would.
//
//   antsim serve scenarios/ghigo1990.toml --port 5025 &
//   node docs/katcp_client.mjs --port 5025 [--host 127.0.0.1] [--source "Cassiopeia A"]
//
// It connects, reads the site and the clock, computes a source's encoder positions with its
// own (low-precision) ephemeris, tracks it with a program-track table, runs one five-point
// cross scan (offsets -4D, -1D, 0, +1D, +4D, D = 7', azimuth steps divided by cos E, 15 s
// integrations), reduces each axis with Clark's method and prints the pointing offsets as
// one JSON line: xel_arcmin and el_arcmin are where the source peaked relative to where the
// client pointed (the correction to add to its positions; indicated minus true).
//
// Ephemeris (good to about half an arcminute, against an 11' beam): B1950 positions
// precessed to the date (IAU 1976, Lieske et al. 1977), Greenwich mean sidereal time (IAU
// 1982) with UTC for UT1; nutation, aberration and the FK4 E-terms are left out. Radio
// refraction: refractivity from the antenna's weather (Smith & Weintraub 1953) times cot E.
// Pointing model: the 1990 model in use (scenarios/ghigo1990.toml, [controller.terms]), in
// the form of controller/pointing/terms.py, or --model W1=-1.6,W6=12.0,... (arcmin; terms
// not given keep their defaults). The offsets printed are what the model leaves: truth minus
// model.

import net from "node:net";

// The 1990 run's sources (scenarios/ghigo1990.toml; Ghigo 1990, Table 1), B1950, degrees.
const SOURCES = {
  "3C84": [49.12333, 41.33111], "Taurus A": [82.87917, 21.98333],
  "Orion A": [83.20417, -5.42083], "3C273": [186.63875, 2.32861],
  "Virgo A": [187.07333, 12.66722], "W31": [271.60667, -20.32667],
  "Cygnus A": [299.435, 40.59611], "Cassiopeia A": [350.2875, 58.54167],
};
const BRIGHT = ["Cassiopeia A", "Taurus A", "Cygnus A", "Orion A"];
const STEP_ARCMIN = 7.0, HPBW_ARCMIN = 11.0, INTEGRATION_S = 15.0, OFFSETS = [-4, -1, 0, 1, 4];
const D2R = Math.PI / 180, AS2R = D2R / 3600;
// Ghigo's W1..W10 in use (arcmin), the 1990 report's (section II), indicated minus true,
// azimuth North-based:
//   dE       = W1 + W2 cos A + W3 sin A + W4 cos E + W5 cot E
//   dA cos E = W6 cos E + (W7 cos A + W8 sin A + W9) sin E + W10
const MODEL = { W1: -1.6, W2: 0.0, W3: -1.8, W4: -2.0, W5: 0.6, W6: 12.0, W7: 1.5, W8: -0.5,
  W9: -3.0, W10: -1.5 };

function option(name, fallback) {
  const i = process.argv.indexOf(`--${name}`);
  return i > 0 && i + 1 < process.argv.length ? process.argv[i + 1] : fallback;
}

// ------------------------------------------------------------------------- KATCP
class Katcp {
  constructor(host, port) {
    this.socket = net.connect({ host, port });
    this.socket.setNoDelay(true);
    this.buffer = "";
    this.mid = 0;
    this.pending = new Map();
    this.opened = new Promise((resolve, reject) => {
      this.socket.once("connect", resolve);
      this.socket.once("error", reject);
    });
    this.socket.on("data", (data) => this.receive(data.toString("utf8")));
  }

  receive(text) {
    this.buffer += text;
    let end;
    while ((end = this.buffer.indexOf("\n")) >= 0) {
      const line = this.buffer.slice(0, end).replace(/\r$/, "");
      this.buffer = this.buffer.slice(end + 1);
      const match = /^([?!#])([A-Za-z][\w-]*)(?:\[(\d+)\])?(.*)$/.exec(line);
      if (!match || match[3] === undefined) continue; // asynchronous informs carry no id
      const call = this.pending.get(Number(match[3]));
      if (!call) continue;
      const args = match[4].trim() === "" ? [] : match[4].trim().split(/ +/).map(unescape);
      if (match[1] === "#") {
        call.informs.push(args);
      } else if (match[1] === "!") {
        this.pending.delete(Number(match[3]));
        if (args[0] === "ok") call.resolve({ values: args.slice(1), informs: call.informs });
        else call.reject(new Error(`?${match[2]} ${args[0]}: ${args.slice(1).join(" ")}`));
      }
    }
  }

  request(name, ...args) {
    const mid = ++this.mid;
    return new Promise((resolve, reject) => {
      this.pending.set(mid, { resolve, reject, informs: [] });
      this.socket.write(`?${name}[${mid}]${args.map((a) => " " + a).join("")}\n`);
    });
  }

  close() { this.socket.end(); }
}

function unescape(arg) {
  const map = { _: " ", "\\": "\\", "@": "", t: "\t", n: "\n", r: "\r", e: "\x1b", 0: "\0" };
  return arg.replace(/\\(.)/g, (_, c) => map[c] ?? c);
}

// ------------------------------------------------------------------------- ephemeris
const JD_J2000 = 2451545.0, JD_B1950 = 2433282.4235;

function jdOfIso(iso) {
  return Date.parse(iso.endsWith("Z") ? iso : iso + "Z") / 86400000 + 2440587.5;
}

function precess(raDeg, decDeg, jdFrom, jdTo) {
  // IAU 1976 precession from one epoch to another (Lieske et al. 1977, eq. 6)
  const T = (jdFrom - JD_J2000) / 36525, t = (jdTo - jdFrom) / 36525;
  const w = 2306.2181 + 1.39656 * T - 0.000139 * T * T;
  const zeta = (w + (0.30188 - 0.000344 * T) * t + 0.017998 * t * t) * t * AS2R;
  const z = (w + (1.09468 + 0.000066 * T) * t + 0.018203 * t * t) * t * AS2R;
  const theta = ((2004.3109 - 0.8533 * T - 0.000217 * T * T) * t
    - (0.42665 + 0.000217 * T) * t * t - 0.041833 * t * t * t) * AS2R;
  const ra = raDeg * D2R, dec = decDeg * D2R;
  const A = Math.cos(dec) * Math.sin(ra + zeta);
  const B = Math.cos(theta) * Math.cos(dec) * Math.cos(ra + zeta) - Math.sin(theta) * Math.sin(dec);
  const C = Math.sin(theta) * Math.cos(dec) * Math.cos(ra + zeta) + Math.cos(theta) * Math.sin(dec);
  return [Math.atan2(A, B) + z, Math.asin(C)]; // radians
}

function gmstRad(jd) {
  const T = (jd - JD_J2000) / 36525;
  const deg = 280.46061837 + 360.98564736629 * (jd - JD_J2000) + 0.000387933 * T * T
    - (T * T * T) / 38710000;
  return (((deg % 360) + 360) % 360) * D2R;
}

function refractivity(weather) {
  const [tempC, pressureHpa, humidity] = weather;
  const tK = tempC + 273.15;
  const e = humidity * 6.1121 * Math.exp((17.502 * tempC) / (240.97 + tempC)); // hPa
  return 77.6 * pressureHpa / tK + 3.73e5 * e / (tK * tK); // N units (1e-6)
}

// The model's offset (indicated minus true, deg) at azimuth and elevation (rad).
function modelOffsetDeg(w, az, el) {
  const tanE = Math.tan(el);
  const dA = w.W6 + (w.W7 * Math.cos(az) + w.W8 * Math.sin(az) + w.W9) * tanE
    + w.W10 / Math.cos(el);
  const dE = w.W1 + w.W2 * Math.cos(az) + w.W3 * Math.sin(az) + w.W4 * Math.cos(el) + w.W5 / tanE;
  return [dA / 60, dE / 60];
}

// Encoder azimuth (North = 0, East = 90) and elevation (deg) of a B1950 source at a UTC
// Julian date: the observed (refracted) place plus the pointing model's offset.
function encoderPosition(source, jd, site, weather, model = MODEL) {
  const [ra, dec] = precess(source[0], source[1], JD_B1950, jd);
  const lat = site.lat * D2R;
  const ha = gmstRad(jd) + site.lon * D2R - ra;
  const sinEl = Math.sin(lat) * Math.sin(dec) + Math.cos(lat) * Math.cos(dec) * Math.cos(ha);
  const el = Math.asin(sinEl);
  const az = Math.atan2(-Math.cos(dec) * Math.sin(ha),
    Math.sin(dec) * Math.cos(lat) - Math.cos(dec) * Math.sin(lat) * Math.cos(ha));
  const observedEl = el + (el > 3 * D2R ? refractivity(weather) * 1e-6 / Math.tan(el) : 0);
  const [dA, dE] = modelOffsetDeg(model, az, observedEl);
  return [(((az / D2R + dA) % 360) + 360) % 360, observedEl / D2R + dE];
}

// ------------------------------------------------------------------------- the scan
function clark(powers) {
  // Clark's method (Ghigo 1990, section VI) with the straight line through the +-4D powers
  // as the baseline: a = (s^2 / 2D) ln[B(+1) / B(-1)], A = B(0) exp(a^2 / 2 s^2)
  const s = HPBW_ARCMIN / 2.3548, D = STEP_ARCMIN;
  const line = (n) => powers[0] + ((powers[4] - powers[0]) * (n + 4)) / 8;
  const b = OFFSETS.map((n, k) => powers[k] - line(n));
  const offset = b[1] > 0 && b[3] > 0 ? ((s * s) / (2 * D)) * Math.log(b[3] / b[1]) : NaN;
  return { offset, amplitude: b[2] * Math.exp((offset * offset) / (2 * s * s)) };
}

async function main() {
  const model = { ...MODEL };
  for (const item of option("model", "").split(",").filter((x) => x)) {
    const [term, value] = item.split("=");
    if (!(term in MODEL) || !Number.isFinite(Number(value))) {
      throw new Error(`--model: ${item} is not TERM=ARCMIN with TERM one of W1..W10`);
    }
    model[term] = Number(value);
  }
  const katcp = new Katcp(option("host", "127.0.0.1"), Number(option("port", "5025")));
  await katcp.opened;
  const info = Object.fromEntries((await katcp.request("antenna")).informs);
  if (info.mount !== "altaz") throw new Error(`this client drives alt-az mounts, not ${info.mount}`);
  const site = { lat: Number(info["site-latitude-deg"]), lon: Number(info["site-longitude-deg"]) };
  const channels = (await katcp.request("channels")).values;
  const [clockS, utc] = (await katcp.request("clock")).values;
  const t0 = Number(clockS), jd0 = jdOfIso(utc);
  const weather = (await katcp.request("weather")).values.map(Number);
  const jdAt = (t) => jd0 + (t - t0) / 86400;

  // the source: the one asked for, else the brightest between 25 and 75 deg elevation
  let name = option("source", null);
  if (name === null) {
    name = BRIGHT.find((n) => {
      const el = encoderPosition(SOURCES[n], jd0, site, weather, model)[1];
      return el > 25 && el < 75;
    });
  }
  if (!(name in SOURCES)) throw new Error(`no source ${name} above 25 deg; try --source`);
  const source = SOURCES[name];

  // a program track for the next 15 minutes, a point every 10 s: time, azimuth, elevation
  const table = [];
  for (let t = t0; t <= t0 + 900; t += 10) {
    const [az, el] = encoderPosition(source, jdAt(t), site, weather, model);
    table.push(t.toFixed(3), az.toFixed(6), el.toFixed(6));
  }
  const [, slewS] = (await katcp.request("track", ...table)).values.map(Number);
  process.stderr.write(`tracking ${name} (slew and settle ${slewS.toFixed(1)} s)\n`);

  const result = { source: name, utc, channels };
  for (const axis of ["az", "el"]) {
    const powers = [];
    for (const n of OFFSETS) {
      const [now] = (await katcp.request("clock")).values.map(Number);
      // the step holds at the middle of the integration, on the sky: divide by cos E there
      const el = encoderPosition(source, jdAt(now + INTEGRATION_S / 2), site, weather, model)[1];
      const step = (n * STEP_ARCMIN) / 60;
      const offset = axis === "az" ? [step / Math.cos(el * D2R), 0] : [0, step];
      await katcp.request("offset", ...offset.map((x) => x.toFixed(8)));
      const v = (await katcp.request("integrate", INTEGRATION_S)).values.map(Number);
      // clock, id, start, end, samples, encoders (2), weather (4), then power, std per channel
      const perChannel = channels.map((_, c) => v[11 + 2 * c]);
      powers.push(perChannel.reduce((a, b) => a + b, 0) / perChannel.length);
      if (axis === "el" && n === 0) {
        result.az_deg = v[5];
        result.el_deg = v[6];
      }
    }
    const { offset, amplitude } = clark(powers);
    result[axis === "az" ? "xel_arcmin" : "el_arcmin"] = offset;
    result[`${axis}_amplitude_k`] = amplitude;
  }
  await katcp.request("offset", 0, 0);
  katcp.close();
  console.log(JSON.stringify(result));
}

main().catch((err) => {
  process.stderr.write(`katcp_client: ${err.message}\n`);
  process.exit(1);
});
