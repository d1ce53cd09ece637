#!/usr/bin/env python3
"""Generate the ray-trace oracle files `<lens>.json` beside this script.

The oracle is an independent optical design code, optiland (PyPI), used only here, offline.
It is NOT a build or test dependency: the Rust test `tests/oracle.rs` reads the JSON files.

Every ray is also traced by a small 50-digit reference tracer written here with mpmath
(centre-based sphere intersection, vector Snell's law); its result says how precise the
oracle itself is. rayoptics (PyPI), a second independent code, is used as a cross-check
when it is installed (it is optional).

Usage (from the repository root, in a throwaway virtual environment):

    python3 -m venv /tmp/oracle-venv
    /tmp/oracle-venv/bin/pip install optiland mpmath rayoptics
    /tmp/oracle-venv/bin/python tests/data/oracle/generate.py

See README.md beside this script for the conventions and the mapping between the codes.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import platform
import sys
import warnings
import xml.etree.ElementTree as ET
from importlib.metadata import version
from pathlib import Path

import mpmath as mpm
import numpy as np

warnings.filterwarnings("ignore")  # optiland deprecations, numba pedantic warnings

from optiland.materials import IdealMaterial  # noqa: E402
from optiland.optic import Optic  # noqa: E402
from optiland.rays import RealRays  # noqa: E402

HERE = Path(__file__).resolve().parent
LAMBDA_D_NM = 587.5618
# optiland's rays start this far in front of the first vertex (see README: a ray that starts
# exactly on the first vertex is a "self-hit" for optiland's root selection).
START_BACKOFF_MM = 10.0
mpm.mp.dps = 50


# --------------------------------------------------------------------------------------------
# Prescriptions
# --------------------------------------------------------------------------------------------


def read_olf_xml(path: Path) -> list[dict]:
    """OpenLensFlare XML: radius 0 = flat, thickness to the next vertex, refractiveIndex of
    the medium after the surface, the last element is the sensor. Values are kept exactly as
    written (parsed from the decimal text to the nearest double)."""
    root = ET.parse(path).getroot()
    out = []
    for e in root.find("elements").findall("element"):
        kind = {"lensSpherical": "refracting", "apertureStop": "stop", "sensor": "sensor"}[
            e.find("type").text.strip()
        ]
        out.append(
            {
                "kind": kind,
                "radius_mm": float(e.find("radius").text),
                "thickness_mm": float(e.find("thickness").text),
                "n_after": float(e.find("refractiveIndex").text),
                "semi_diameter_mm": float(e.find("height").text),
            }
        )
    assert out[-1]["kind"] == "sensor"
    return out


def read_pbrt_csv(path: Path) -> list[dict]:
    """The PBRT dgauss 50 mm table as CSV: radius (0 = the stop), thickness to the next
    vertex, nd after, aperture diameter. The last thickness is 0 (PBRT focuses itself): the
    sensor plane is placed by the caller."""
    out = []
    for line in path.read_text().splitlines():
        if line.startswith("#") or line.startswith("surface"):
            continue
        f = line.split(",")
        stop = f[6].strip() == "1"
        out.append(
            {
                "kind": "stop" if stop else "refracting",
                "radius_mm": float(f[1]),
                "thickness_mm": float(f[2]),
                "n_after": float(f[3]),
                "semi_diameter_mm": float(f[5]),
            }
        )
    out.append(
        {"kind": "sensor", "radius_mm": 0.0, "thickness_mm": 0.0, "n_after": 1.0,
         "semi_diameter_mm": 21.6333}
    )
    return out


def vertex_z(pres: list[dict]) -> list[float]:
    """Vertex positions as the SDK computes them: a running f64 sum from 0."""
    z, out = 0.0, []
    for s in pres:
        out.append(z)
        z += s["thickness_mm"]
    return out


# --------------------------------------------------------------------------------------------
# The oracle: optiland
# --------------------------------------------------------------------------------------------


def build_optiland(pres: list[dict]) -> Optic:
    lens = Optic()
    lens.surfaces.add(index=0, thickness=np.inf, material=IdealMaterial(n=1.0))
    for i, s in enumerate(pres[:-1]):
        r = s["radius_mm"]
        lens.surfaces.add(
            index=i + 1,
            radius=np.inf if r == 0.0 else r,
            thickness=s["thickness_mm"],
            material=IdealMaterial(n=s["n_after"]),
            is_stop=s["kind"] == "stop",
        )
    lens.surfaces.add(index=len(pres))  # image surface = our sensor
    stop = next(s for s in pres if s["kind"] == "stop")
    lens.set_aperture(aperture_type="float_by_stop_size", value=2.0 * stop["semi_diameter_mm"])
    lens.fields.set_type("angle")
    lens.fields.add(y=0.0)
    lens.wavelengths.add(value=LAMBDA_D_NM * 1e-3, is_primary=True)
    return lens


def optiland_paraxial(lens: Optic, pres: list[dict]) -> dict:
    p = lens.paraxial
    efl = float(np.ravel(p.f2())[0])
    # F2 is measured from the image surface; BFL from the last refracting vertex.
    bfl = float(np.ravel(p.F2())[0]) + pres[-2]["thickness_mm"]
    return {
        "efl_mm": efl,
        "bfl_mm": bfl,
        "entrance_pupil_z_mm": float(np.ravel(p.EPL())[0]),
        "entrance_pupil_radius_mm": float(np.ravel(p.EPD())[0]) / 2.0,
    }


def optiland_trace(lens: Optic, rays: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """Positions and directions after every surface: arrays (surface, ray, 3)."""
    o = np.array([r["origin"] for r in rays])
    d = np.array([r["dir"] for r in rays])
    s = -START_BACKOFF_MM / d[:, 2]
    start = o + s[:, None] * d
    n = len(rays)
    rr = RealRays(start[:, 0], start[:, 1], start[:, 2], d[:, 0], d[:, 1], d[:, 2],
                  np.ones(n), np.full(n, LAMBDA_D_NM * 1e-3))
    sg = lens.surfaces
    sg.trace(rr, skip=1)  # skip the object surface at infinity; no apertures are set
    pos = np.stack([np.asarray(sg.x), np.asarray(sg.y), np.asarray(sg.z)], axis=-1)
    dirs = np.stack([np.asarray(sg.L), np.asarray(sg.M), np.asarray(sg.N)], axis=-1)
    return pos, dirs


# --------------------------------------------------------------------------------------------
# The 50-digit reference (precision check of the oracle)
# --------------------------------------------------------------------------------------------


def mp_trace(pres: list[dict], origin, direction):
    """Centre-based sphere intersection and vector Snell's law in 50 digits, starting from the
    exact binary values of `origin`/`direction` at z = 0. Vertex positions are the exact sums
    of the f64 thicknesses."""
    p = [mpm.mpf(v) for v in origin]
    d = [mpm.mpf(v) for v in direction]
    # Back off along the line so that the first surface lies ahead of the start.
    p = [p[k] - mpm.mpf(START_BACKOFF_MM) / d[2] * d[k] for k in range(3)]
    zv = mpm.mpf(0)
    n_before = mpm.mpf(1)
    hits = []
    for i, s in enumerate(pres):
        if i > 0:
            zv += mpm.mpf(pres[i - 1]["thickness_mm"])
        r = mpm.mpf(s["radius_mm"])
        if r == 0:
            t = (zv - p[2]) / d[2]
            h = [p[k] + t * d[k] for k in range(3)]
            nrm = [mpm.mpf(0), mpm.mpf(0), mpm.mpf(1)]
        else:
            c = [mpm.mpf(0), mpm.mpf(0), zv + r]
            oc = [p[k] - c[k] for k in range(3)]
            b = sum(oc[k] * d[k] for k in range(3))
            q = sum(oc[k] ** 2 for k in range(3)) - r * r
            disc = b * b - q
            assert disc >= 0, f"mp reference: ray misses surface {i}"
            roots = [-b - mpm.sqrt(disc), -b + mpm.sqrt(disc)]
            # The first hit ahead of the ray on the sheet through the vertex (the vertex
            # side of the centre).
            cand = [t for t in roots if t > 0 and (c[2] - (p[2] + t * d[2])) * mpm.sign(r) > 0]
            assert cand, f"mp reference: no forward hit on the vertex sheet of surface {i}"
            t = min(cand)
            h = [p[k] + t * d[k] for k in range(3)]
            nrm = [(c[k] - h[k]) / r for k in range(3)]  # unit, +z at the vertex
        if s["kind"] != "sensor":
            n_after = mpm.mpf(s["n_after"])
            mu = n_before / n_after
            cos_i = sum(d[k] * nrm[k] for k in range(3))
            if cos_i < 0:
                nrm = [-v for v in nrm]
                cos_i = -cos_i
            root = mpm.sqrt(1 - mu * mu * (1 - cos_i * cos_i))
            d = [mu * d[k] + (root - mu * cos_i) * nrm[k] for k in range(3)]
            n_before = n_after
        p = h
        hits.append((h, d))
    return hits


# --------------------------------------------------------------------------------------------
# Cross-check: rayoptics (optional)
# --------------------------------------------------------------------------------------------


def rayoptics_trace(pres: list[dict], rays: list[dict]):
    try:
        from rayoptics.optical.opticalmodel import OpticalModel
        from rayoptics.raytr import raytrace as rt
        from rayoptics.raytr.opticalspec import FieldSpec, PupilSpec, WvlSpec
    except ImportError:
        return None
    opm = OpticalModel()
    sm = opm["seq_model"]
    osp = opm["optical_spec"]
    stop = next(s for s in pres if s["kind"] == "stop")
    osp["pupil"] = PupilSpec(osp, key=["object", "pupil"], value=2 * stop["semi_diameter_mm"])
    osp["fov"] = FieldSpec(osp, key=["object", "angle"], value=0.0, flds=[0.0])
    osp["wvls"] = WvlSpec([(LAMBDA_D_NM, 1.0)], ref_wl=0)
    opm.radius_mode = True
    sm.gaps[0].thi = START_BACKOFF_MM
    for s in pres[:-1]:
        sm.add_surface([s["radius_mm"], s["thickness_mm"], s["n_after"]])
        if s["kind"] == "stop":
            sm.set_stop()
    opm.update_model()
    zv = vertex_z(pres)
    out = []
    for r in rays:
        o = np.array(r["origin"])
        d = np.array(r["dir"])
        start = o + (-START_BACKOFF_MM / d[2]) * d
        start[2] += START_BACKOFF_MM  # object-interface coordinates (its vertex at z = -10)
        ray, _, _ = rt.trace_raw(sm.path(wl=LAMBDA_D_NM), start, d, LAMBDA_D_NM,
                                 intersect_obj=False)
        # ray[0] is the start, ray[1..] the surfaces; points are vertex-local.
        hits = []
        for k, seg in enumerate(ray[1:]):
            pt = np.array(seg[0], dtype=float)
            pt[2] += zv[k]
            hits.append((pt, np.array(seg[1], dtype=float)))
        out.append(hits)
    return out


# --------------------------------------------------------------------------------------------
# Rays
# --------------------------------------------------------------------------------------------


def collimated(field_deg: float, azimuth_deg: float, height_mm: float) -> dict:
    """Exactly `Ray::collimated(field.to_radians(), azimuth.to_radians(), height)`."""
    a, p = math.radians(field_deg), math.radians(azimuth_deg)
    sa, ca, sp, cp = math.sin(a), math.cos(a), math.sin(p), math.cos(p)
    return {
        "kind": "collimated",
        "field_deg": field_deg,
        "azimuth_deg": azimuth_deg,
        "height_mm": height_mm,
        "origin": [-height_mm * sp, height_mm * cp, 0.0],
        "dir": [-sa * sp, sa * cp, ca],
    }


def skew(field_deg: float, px: float, py: float, ep_z: float) -> dict:
    """A ray of a field in the y–z plane through the entrance-pupil point (px, py), given as an
    explicit origin on z = 0 and unit direction (not expressible with `Ray::collimated`)."""
    a = math.radians(field_deg)
    sa, ca = math.sin(a), math.cos(a)
    return {
        "kind": "skew",
        "field_deg": field_deg,
        "pupil_mm": [px, py],
        "origin": [px, py - ep_z * sa / ca, 0.0],
        "dir": [0.0, sa, ca],
    }


def make_rays(fields: list[float], ep_z: float, ep_r: float, fits) -> list[dict]:
    """Per field: five meridional heights across the entrance pupil, two meridional rays of
    a field rotated to azimuth 30°, two skew rays. A pupil fraction is shrunk (× 0.85 at a
    time) until the ray passes inside every clear semi-diameter (`fits`), so that no ray
    relies on surfaces that cross each other outside their apertures."""
    rays = []

    def add(make, frac):
        for _ in range(40):
            ray = make(frac)
            if fits(ray):
                rays.append(ray)
                return
            frac = tuple(f * 0.85 for f in frac)
        raise RuntimeError(f"no fitting ray near {make(frac)}")

    for f in fields:
        chief = -ep_z * math.tan(math.radians(f))
        for frac in (-0.9, -0.5, 0.0, 0.5, 0.9):
            add(lambda fr, f=f, c=chief: collimated(f, 0.0, round(c + fr[0] * ep_r, 6)), (frac,))
        for frac in (-0.7, 0.7):
            add(lambda fr, f=f, c=chief: collimated(f, 30.0, round(c + fr[0] * ep_r, 6)), (frac,))
        add(lambda fr, f=f: skew(f, round(fr[0] * ep_r, 6), round(fr[1] * ep_r, 6), ep_z),
            (0.7, 0.0))
        add(lambda fr, f=f: skew(f, round(fr[0] * ep_r, 6), round(fr[1] * ep_r, 6), ep_z),
            (0.5, -0.5))
    return rays


# --------------------------------------------------------------------------------------------


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def vmax(a) -> float:
    return float(np.max(np.abs(a))) if np.size(a) else 0.0


def generate(name: str, lens_file: str, src: Path, src_label: str, fields: list[float],
             image_plane: str) -> dict:
    pres = read_olf_xml(src) if src.suffix == ".xml" else read_pbrt_csv(src)
    lens = build_optiland(pres)
    par = optiland_paraxial(lens, pres)
    zv = vertex_z(pres)
    if image_plane == "paraxial_focus":
        # The sensor at the oracle's paraxial focus, stated explicitly in the JSON.
        pres[-2]["thickness_mm"] = par["bfl_mm"]
        lens = build_optiland(pres)
        zv = vertex_z(pres)
    oz = np.asarray(lens.surfaces.global_z_positions).ravel()[1:]
    assert np.max(np.abs(oz - np.array(zv))) < 1e-12, (oz, zv)

    def fits(ray: dict) -> bool:
        pos, _ = optiland_trace(lens, [ray])
        if not np.all(np.isfinite(pos)):
            return False
        rel = [math.hypot(*pos[k, 0, :2]) / s["semi_diameter_mm"] for k, s in
               enumerate(pres[:-1])]
        return max(rel) <= 1.0

    rays = make_rays(fields, par["entrance_pupil_z_mm"], par["entrance_pupil_radius_mm"], fits)
    pos, dirs = optiland_trace(lens, rays)
    assert np.all(np.isfinite(pos)) and np.all(np.isfinite(dirs)), f"{name}: a ray failed"
    ro = rayoptics_trace(pres, rays)

    err_p = err_d = ro_p = ro_d = 0.0
    for j, r in enumerate(rays):
        ref = mp_trace(pres, r["origin"], r["dir"])
        r["hits"] = []
        for k, (hp, hd) in enumerate(ref):
            mp_pos = [float(v) for v in hp]
            mp_dir = [float(v) for v in hd]
            hit = {
                "surface": k,
                "position": [float(v) for v in pos[k, j]],
                "direction": [float(v) for v in dirs[k, j]],
                "position_ref50": mp_pos,
                "direction_ref50": mp_dir,
            }
            err_p = max(err_p, vmax(np.array(hit["position"]) - np.array(mp_pos)))
            err_d = max(err_d, vmax(np.array(hit["direction"]) - np.array(mp_dir)))
            if ro is not None:
                ro_p = max(ro_p, vmax(ro[j][k][0] - pos[k, j]))
                ro_d = max(ro_d, vmax(ro[j][k][1] - dirs[k, j]))
            r["hits"].append(hit)
        r["max_relative_radius"] = max(
            math.hypot(h["position"][0], h["position"][1]) / s["semi_diameter_mm"]
            for h, s in zip(r["hits"][:-1], pres[:-1])
        )

    precision = {
        "reference": "50-digit mpmath tracer in generate.py (centre-based sphere "
        "intersection, vector Snell), from the same f64 inputs",
        "oracle_vs_reference_max_position_mm": err_p,
        "oracle_vs_reference_max_direction": err_d,
    }
    if ro is not None:
        precision["rayoptics_version"] = version("rayoptics")
        precision["rayoptics_vs_oracle_max_position_mm"] = ro_p
        precision["rayoptics_vs_oracle_max_direction"] = ro_d

    return {
        "schema": 1,
        "lens": name,
        "lens_file": lens_file,
        "source": {"path": src_label, "sha256": sha256(src)},
        "oracle": {
            "name": "optiland",
            "version": version("optiland"),
            "numpy": np.__version__,
            "python": platform.python_version(),
            "precision": "float64 (numpy backend)",
        },
        "wavelength_nm": LAMBDA_D_NM,
        "media": "constant index nd everywhere (IdealMaterial), object space n = 1",
        "apertures": "none in the oracle (geometry only)",
        "start": f"optiland rays start {START_BACKOFF_MM} mm in front of z = 0 on the same line",
        "prescription": pres,
        "vertex_z_mm": zv,
        "image_plane": image_plane,
        "image_plane_z_mm": zv[-1],
        "paraxial": par,
        "precision": precision,
        "rays": rays,
    }


LENSES = [
    # name, file in the repo, source, fields (degrees), image plane
    ("heliar-tronnier", "openlensflare/heliar-tronnier.xml", [0.0, 6.0, 12.0], "file_sensor"),
    ("nikon-zoom-short", "openlensflare/nikon-zoom-short.xml", [0.0, 7.0, 14.0], "file_sensor"),
    ("canon-zoom-short", "openlensflare/canon-zoom-short.xml", [0.0, 8.0, 16.0], "file_sensor"),
    ("double-gauss-50mm", "csv/pbrt_dgauss.50mm.csv", [0.0, 10.0, 20.0], "paraxial_focus"),
]


def dump(doc: dict) -> str:
    """Indented JSON with one line per hit (shortest round-trip float repr)."""
    rays = doc.pop("rays")
    head = json.dumps(doc, indent=1)
    lines = []
    for r in rays:
        hits = r.pop("hits")
        body = json.dumps(r)[:-1]
        hl = ",\n   ".join(json.dumps(h) for h in hits)
        lines.append(f'  {body}, "hits": [\n   {hl}\n  ]}}')
        r["hits"] = hits
    doc["rays"] = rays
    return head[:-2] + ',\n "rays": [\n' + ",\n".join(lines) + "\n ]\n}\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sources", default=str(HERE.parents[2] / "lenses" / "sources"),
                    help="the original lens files (default: the repository's lenses/sources/)")
    ap.add_argument("--out", default=str(HERE))
    args = ap.parse_args()
    for name, rel, fields, image_plane in LENSES:
        src = Path(args.sources) / rel
        doc = generate(name, f"lenses/{name}.xml", src, f"lenses/sources/{rel}", fields, image_plane)
        out = Path(args.out) / f"{name}.json"
        out.write_text(dump(doc))
        pr = doc["precision"]
        print(f"{name}: {len(doc['rays'])} rays, EFL {doc['paraxial']['efl_mm']:.6f} mm, "
              f"oracle vs 50-digit: {pr['oracle_vs_reference_max_position_mm']:.2e} mm, "
              f"{pr['oracle_vs_reference_max_direction']:.2e}; rayoptics vs oracle: "
              f"{pr.get('rayoptics_vs_oracle_max_position_mm', float('nan')):.2e} mm, "
              f"{pr.get('rayoptics_vs_oracle_max_direction', float('nan')):.2e}",
              file=sys.stderr)


if __name__ == "__main__":
    main()
