#!/usr/bin/env python3
"""Builds the lens library (lenses/*.xml) from the source files in lenses/sources/.

    python3 lenses/sources/convert.py

Standard library only. Reads:
  sources/openlensflare/*.xml   OpenLensFlare example systems (BSD-2-Clause)
  sources/csv/*.csv             prescriptions as CSV with provenance headers; systems.csv holds
                                the global attributes and patents of the OpenLensFlare systems
  ../../sdk/data/glass_catalog.csv  catalogue nd/Vd for named glasses
and writes lenses/<name>.xml in flarebench's XML (docs/formats.md), byte for byte what
flarebench's own writer produces for the same system, plus the lens table in lenses/README.md.

Conventions (docs/ARCHITECTURE.md section 4): millimetres; surfaces front to sensor; radius 0 is flat;
refractive index and Abbe number describe the medium after a surface; `height` is the clear
semi-diameter. Paraxial values below are at the d line (587.56 nm), object at infinity.
"""

import csv
import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from decimal import Decimal
from pathlib import Path

HERE = Path(__file__).resolve().parent
LENSES = HERE.parent
OLF_DIR = HERE / "openlensflare"
CSV_DIR = HERE / "csv"

OLF_SOURCE = (
    "OpenLensFlare example system, github.com/csobaistvan/OpenLensFlare "
    "OpenLensFlare/examples/systems/{file} (BSD-2-Clause)"
)
FILM = (36.0, 24.0)
# Sensor semi-diameter for sensors we add: the 36 x 24 mm film's half diagonal, rounded up.
FILM_HALF_DIAGONAL = math.ceil(math.hypot(*FILM) / 2 * 10) / 10
AIR_ABBE = "89.3"  # what OpenLensFlare's files give air; ignored when reading (n = 1 is air)


# --- the model --------------------------------------------------------------------------------


@dataclass
class Surface:
    kind: str  # lensSpherical | apertureStop | sensor
    radius: float  # 0 = flat
    thickness: float  # to the next vertex
    sd: float  # clear semi-diameter
    nd: float = 1.0  # medium after the surface; 1 = air
    vd: float | None = None  # None: non-dispersive (written as abbeNumber inf)
    glass: str | None = None  # catalogue name; nd/vd then come from the catalogue
    coating: tuple[float, float] | None = None  # (design wavelength nm, layer index)
    mask: str | None = None
    mask_ft: str | None = None

    @property
    def curvature(self) -> float:
        return 0.0 if self.radius == 0 or math.isinf(self.radius) else 1.0 / self.radius


@dataclass
class Lens:
    name: str
    surfaces: list[Surface]
    source: str
    notes: list[str] = field(default_factory=list)
    fnumber: float | None = None
    efl: float | None = None  # the focal length the source states
    fov: float | None = None  # full field of view the source states, degrees
    film: tuple[float, float] = FILM


# --- glass catalogue --------------------------------------------------------------------------


def load_catalog() -> dict[str, tuple[float, float]]:
    """`CATALOG:NAME` (upper case) -> listed (nd, vd)."""
    table = {}
    with open(LENSES.parent / "sdk" / "data" / "glass_catalog.csv", newline="") as f:
        rows = csv.reader(line for line in f if not line.startswith("#"))
        next(rows)  # header
        for row in rows:
            table[f"{row[0].upper()}:{row[1].upper()}"] = (float(row[6]), float(row[7]))
    return table


CATALOG = load_catalog()


def glass_name(name: str) -> str:
    """Canonical `SCHOTT:NAME` for a Zemax glass (GCAT SCHOTT)."""
    key = name.upper() if ":" in name else f"SCHOTT:{name.upper()}"
    if key not in CATALOG:
        raise SystemExit(f"glass {name} is not in sdk/data/glass_catalog.csv")
    return key


# --- paraxial (ynu) trace -----------------------------------------------------------------------


def index_after(s: Surface) -> float:
    return CATALOG[s.glass][0] if s.glass else s.nd


def trace(surfaces: list[Surface], y: float, u: float):
    """Traces a paraxial ray (height y, angle u in object space) to the last surface before
    the sensor. Returns the heights at every surface and (y, u) just after the last one."""
    heights = []
    n = 1.0
    optics = [s for s in surfaces if s.kind != "sensor"]
    for i, s in enumerate(optics):
        heights.append(y)
        n2 = index_after(s)
        u = (n * u - y * s.curvature * (n2 - n)) / n2
        n = n2
        if i + 1 < len(optics):
            y += s.thickness * u
    return heights, y, u


@dataclass
class Paraxial:
    efl: float
    bfl: float  # last vertex to the rear focus
    epd_open: float  # entrance pupil diameter with the stop wide open
    focus_error: float  # sensor minus paraxial focus (positive: sensor behind focus)

    @property
    def f_open(self) -> float:
        return abs(self.efl) / self.epd_open


def paraxial(lens: Lens) -> Paraxial:
    """First-order data from the ray entering parallel to the axis at height 1."""
    heights, y, u = trace(lens.surfaces, 1.0, 0.0)
    efl, bfl = -1.0 / u, -y / u
    stop = stop_index(lens)
    epd = 2 * lens.surfaces[stop].sd / abs(heights[stop])
    return Paraxial(efl, bfl, epd, lens.surfaces[-2].thickness - bfl)


def stop_index(lens: Lens) -> int:
    stops = [i for i, s in enumerate(lens.surfaces) if s.kind == "apertureStop"]
    assert len(stops) == 1, f"{lens.name}: {len(stops)} stops"
    return stops[0]


def ray_heights(lens: Lens, pupil_radius: float, field_deg: float):
    """Marginal ray heights for an entrance pupil of `pupil_radius`, and chief ray heights at
    `field_deg`, at every surface before the sensor (linear combinations of two base rays)."""
    a, _, _ = trace(lens.surfaces, 1.0, 0.0)
    b, _, _ = trace(lens.surfaces, 0.0, 1.0)
    stop = stop_index(lens)
    u0 = math.tan(math.radians(field_deg))
    y0 = -u0 * b[stop] / a[stop]  # the chief ray crosses the axis at the stop
    marginal = [pupil_radius * ya for ya in a]
    chief = [y0 * ya + u0 * yb for ya, yb in zip(a, b)]
    return marginal, chief


# --- writing (mirrors sdk/src/io/olf_xml/write.rs) ----------------------------------------------


def num(v: float) -> str:
    """Rust's `{}` for f64: shortest round-trip digits, never an exponent."""
    if math.isinf(v):
        return "inf" if v > 0 else "-inf"
    s = format(Decimal(repr(float(v))), "f")
    if "." in s:
        s = s.rstrip("0").rstrip(".")
    return s


def radius_text(c: float) -> str:
    """The shortest decimal radius whose reciprocal is exactly `c`; 0 when flat."""
    if c == 0:
        return "0"
    r = 1.0 / c
    for digits in range(17):
        v = float(f"{r:.{digits}e}")
        if 1.0 / v == c:
            return num(v)
    return num(r)


def esc(s: str) -> str:
    return s.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def to_xml(lens: Lens) -> str:
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        "<!-- OpenLensFlare optical system with flarebench extensions (docs/formats.md) -->",
        "<opticalSystem>",
    ]

    def tag(indent: int, name: str, value: str):
        out.append(f"{' ' * indent}<{name}>{value}</{name}>")

    tag(4, "name", esc(lens.name))
    for name, value in [
        ("fnumber", lens.fnumber),
        ("effectiveFocalLength", lens.efl),
        ("fieldOfView", lens.fov),
    ]:
        if value is not None:
            tag(4, name, num(value))
    tag(4, "filmWidth", num(lens.film[0]))
    tag(4, "filmHeight", num(lens.film[1]))
    tag(4, "source", esc(lens.source.strip()))
    tag(4, "notes", esc("\n".join(lens.notes).strip()))
    out.append("    <elements>")
    for s in lens.surfaces:
        out.append("        <element>")
        tag(12, "type", s.kind)
        tag(12, "height", num(s.sd))
        tag(12, "thickness", num(s.thickness))
        c = s.curvature
        tag(12, "radius", radius_text(c))
        tag(12, "curvature", num(c))
        if s.glass:
            nd, vd = CATALOG[s.glass]
            tag(12, "refractiveIndex", num(nd))
            tag(12, "abbeNumber", num(vd))
            tag(12, "glass", esc(s.glass))
        elif s.nd == 1.0:
            tag(12, "refractiveIndex", "1")
            tag(12, "abbeNumber", AIR_ABBE)
        else:
            tag(12, "refractiveIndex", num(s.nd))
            tag(12, "abbeNumber", "inf" if s.vd is None else num(s.vd))
        lam, ior = s.coating or (0.0, 0.0)
        tag(12, "coatingLambda", num(lam))
        tag(12, "coatingIor", num(ior))
        if s.mask:
            tag(12, "mask", esc(s.mask))
        if s.mask_ft:
            tag(12, "maskFT", esc(s.mask_ft))
        out.append("        </element>")
    out += ["    </elements>", "</opticalSystem>", ""]
    return "\n".join(out)


# --- readers ----------------------------------------------------------------------------------


def read_csv(path: Path):
    """The `#` header lines and the rows (as dicts) of a lenses-csv file."""
    lines = path.read_text().splitlines()
    header = [l[1:].strip() for l in lines if l.startswith("#")]
    rows = list(csv.DictReader(l for l in lines if not l.startswith("#")))
    return header, rows


def systems_table() -> dict[str, dict]:
    _, rows = read_csv(CSV_DIR / "systems.csv")
    return {r["name"]: r for r in rows}


def olf_surface(kind, radius, thickness, sd, nd, vd, lam, ior, mask, mask_ft) -> Surface:
    coating = (lam, ior) if lam != 0 and ior != 0 else None
    return Surface(
        kind=kind,
        radius=radius,
        thickness=thickness,
        sd=sd,
        nd=nd,
        vd=vd if nd != 1.0 else None,
        coating=coating,
        mask=mask or None,
        mask_ft=mask_ft or None,
    )


def from_olf_xml(path: Path) -> Lens:
    root = ET.parse(path).getroot()
    get = lambda e, t: (e.findtext(t) or "").strip()
    surfaces = []
    for e in root.find("elements"):
        f = lambda t: float(get(e, t) or 0)
        surfaces.append(
            olf_surface(
                get(e, "type"), f("radius"), f("thickness"), f("height"),
                f("refractiveIndex"), f("abbeNumber"), f("coatingLambda"), f("coatingIor"),
                get(e, "mask"), get(e, "maskFT"),
            )
        )
    return Lens(
        name=get(root, "name"),
        surfaces=surfaces,
        source=OLF_SOURCE.format(file=path.name),
        fnumber=float(get(root, "fnumber")),
        efl=float(get(root, "effectiveFocalLength")),
        fov=float(get(root, "fieldOfView")),
        film=(float(get(root, "filmWidth")), float(get(root, "filmHeight"))),
    )


def from_olf_csv(path: Path, system: dict) -> Lens:
    """An OpenLensFlare system given as CSV (one row per element, OpenLensFlare's columns)."""
    _, rows = read_csv(path)
    surfaces = [
        olf_surface(
            r["type"], float(r["radius_mm"]), float(r["thickness_mm"]),
            float(r["height_semi_aperture_mm"]), float(r["n_d_after"]), float(r["V_d_after"]),
            float(r["coating_lambda_nm"]), float(r["coating_ior"]), r["mask"], r["mask_ft"],
        )
        for r in rows
    ]
    return Lens(
        name=system["name"],
        surfaces=surfaces,
        source=OLF_SOURCE.format(file=system["source_file"])
        + f"; read from its CSV transcription lenses/sources/csv/{path.name}",
        fnumber=float(system["fnumber"]),
        efl=float(system["effective_focal_length_mm"]),
        fov=float(system["field_of_view_deg"]),
        film=(float(system["film_width_mm"]), float(system["film_height_mm"])),
    )


def from_pbrt_csv(path: Path, name: str) -> Lens:
    """A PBRT realistic-camera table: nd only, aperture diameters, last thickness 0 = focus."""
    _, rows = read_csv(path)
    surfaces = []
    for r in rows:
        stop = r["is_stop"] == "1"
        surfaces.append(
            Surface(
                kind="apertureStop" if stop else "lensSpherical",
                radius=float(r["radius_mm"]),
                thickness=float(r["thickness_mm"]),
                sd=float(r["semi_diameter_mm"]),
                nd=float(r["n_d_after"]),
                vd=None,
            )
        )
    surfaces.append(Surface("sensor", 0.0, 0.0, FILM_HALF_DIAGONAL))
    lens = Lens(name=name, surfaces=surfaces, source="")
    assert surfaces[-2].thickness == 0, f"{path.name}: last thickness is not 0"
    surfaces[-2].thickness = round(paraxial(lens).bfl, 6)
    return lens


def mm(text: str) -> float:
    """A length from a Zemax-derived table, rounded to 1e-6 mm: the tables carry float32
    noise (5.514017105102539) and inch conversion noise (6.324599999999999)."""
    v = float(text)
    return v if math.isinf(v) else round(v, 6)


def from_zemax_csv(path: Path, name: str) -> Lens:
    """A Zemax-derived table: skips the object surface and flat air-to-air dummy surfaces
    (a leading one with its gap; others fold their thickness into the surface before)."""
    _, rows = read_csv(path)
    rows = rows[1:]  # surface 0 is the object
    surfaces: list[Surface] = []
    for i, r in enumerate(rows):
        radius = mm(r["radius_mm"])
        flat = math.isinf(radius)
        glass = r["glass"].upper()
        last = i == len(rows) - 1
        stop = r["is_stop"] == "1"
        if last:
            surfaces.append(Surface("sensor", 0.0, 0.0, FILM_HALF_DIAGONAL))
            continue
        before_is_air = not surfaces or surfaces[-1].nd == 1.0 and not surfaces[-1].glass
        if flat and glass == "AIR" and before_is_air and not stop:
            if surfaces:
                surfaces[-1].thickness = round(surfaces[-1].thickness + mm(r["thickness_mm"]), 6)
            continue
        sd = mm(r["semi_diameter_mm"] or "0")
        surfaces.append(
            Surface(
                kind="apertureStop" if stop else "lensSpherical",
                radius=0.0 if flat else radius,
                thickness=mm(r["thickness_mm"]),
                sd=sd,
                glass=None if glass == "AIR" else glass_name(glass),
            )
        )
    return Lens(name=name, surfaces=surfaces, source="")


def from_lff_csv(path: Path, name: str) -> Lens:
    """LensFlareFramework's Heliar: semi-diameters already halved in the CSV."""
    _, rows = read_csv(path)
    surfaces = [
        olf_surface(
            r["type"], float(r["radius_mm"]), float(r["thickness_mm"]),
            float(r["semi_diameter_mm"]), float(r["n_d_after"]), float(r["V_d_after"]),
            float(r["coating_lambda_nm"]), float(r["coating_n"]), "", "",
        )
        for r in rows
    ]
    return Lens(name=name, surfaces=surfaces, source="")


# --- the library ------------------------------------------------------------------------------


def header_value(header: list[str], key: str) -> str:
    """`KEY=value` from a CSV's `# Header:` line."""
    for line in header:
        m = re.search(rf"\b{key}=([^;]+)", line)
        if m:
            return m.group(1).strip()
    raise KeyError(key)


def aperture_note(lens: Lens, p: Paraxial) -> str | None:
    if lens.fnumber is not None and p.f_open > lens.fnumber * 1.005:
        return (
            f"The stop wide open gives f/{p.f_open:.2f} (paraxial), slower than the stated "
            f"f/{num(lens.fnumber)}: the f-number setting leaves the stop wide open."
        )
    return None


def focus_note(p: Paraxial) -> str | None:
    if abs(p.focus_error) > 0.05:
        where = "behind" if p.focus_error > 0 else "in front of"
        return (
            f"The sensor is {abs(p.focus_error):.2f} mm {where} the paraxial focus "
            f"(back focal distance {p.bfl:.3f} mm)."
        )
    return None


def efl_note(lens: Lens, p: Paraxial) -> str:
    text = f"Paraxial EFL at the d line: {p.efl:.2f} mm"
    if lens.efl is not None:
        text += f" (the source states {num(lens.efl)} mm)"
    return text + "."


OLF_COATING_NOTE = (
    "Coatings: a quarter-wave single layer designed for 620 nm with index 1.38 on every "
    "refracting surface, as in the OpenLensFlare file."
)


def olf_lenses(systems: dict[str, dict]) -> list[tuple[str, Lens]]:
    """The OpenLensFlare systems: its ten XML files, and the two it has only as CSV here."""
    out = [(path.stem.lower(), from_olf_xml(path)) for path in OLF_DIR.glob("*.xml")]
    from_xml = {stem for stem, _ in out}
    for stem in ["itoh-zoom-mid", "kreitzer-tele"]:
        out.append((stem, from_olf_csv(CSV_DIR / f"{stem}.csv", systems[stem])))
    out.sort(key=lambda entry: entry[0])
    for stem, lens in out:
        row = systems[lens.name]
        p = paraxial(lens)
        notes = [f"Design: {row['patent_source']}."]
        if row["notes"]:
            notes.append(f"OpenLensFlare data note: {row['notes']}.")
        notes.append(efl_note(lens, p))
        if lens.efl and abs(p.efl - lens.efl) > 0.02 * lens.efl:
            notes.append(
                "The stated focal length does not match the surfaces; it is kept as the "
                "file gives it (informational only)."
            )
        notes += [n for n in (aperture_note(lens, p), focus_note(p)) if n]
        notes.append(OLF_COATING_NOTE)
        if stem in from_xml:
            notes.append(
                "Converted without changes from the OpenLensFlare XML (its values keep "
                "their float32 rounding)."
            )
        lens.notes = notes
        lens.name = stem
    return out


PBRT = [
    # (file stem, csv, stated EFL, f-number stated, full FOV stated, design note)
    ("double-gauss-50mm", "pbrt_dgauss.50mm.csv", 50.0, 2.0, 44.0,
     "Double Gauss F/2, 22 degrees half field: US 2,673,491 (Tronnier), from W. Smith, "
     "Modern Lens Design p. 312, scaled to 50 mm."),
    ("wide-22mm", "pbrt_wide.22mm.csv", 22.0, None, None,
     "Wide-angle lens (Nakamura), W. Smith, Modern Lens Design p. 360, scaled to 22 mm; the "
     "PBRT header calls it a 38-degree lens without saying whether that is the full or the "
     "half field, so no field of view is given here."),
    ("telephoto-250mm", "pbrt_telephoto.250mm.csv", 250.0, None, None,
     "Telephoto lens from PBRT's lens set, 250 mm."),
    ("fisheye-10mm", "pbrt_fisheye.10mm.csv", 10.0, 4.0, 155.9,
     "Muller 16 mm f/4 fisheye, 155.9 degrees field, W. Smith, Modern Lens Design p. 164, "
     "scaled to 10 mm."),
]


def pbrt_lenses() -> list[tuple[str, Lens]]:
    out = []
    for stem, file, efl, fno, fov, design in PBRT:
        header, _ = read_csv(CSV_DIR / file)
        origin = header[0].removeprefix("Source: ").strip()
        lens = from_pbrt_csv(CSV_DIR / file, stem)
        lens.efl, lens.fnumber, lens.fov = efl, fno, fov
        lens.source = (
            f"PBRT realistic-camera lens table, github.com/mmp/pbrt-v4-scenes {origin}, "
            f"via lenses/sources/csv/{file}; the repository states no licence for the lens tables "
            "(published patent data)."
        )
        p = paraxial(lens)
        notes = [
            f"Design: {design}",
            efl_note(lens, p),
            "PBRT tables give nd only: every glass is a non-dispersive model glass "
            "(abbeNumber inf), so this lens shows no chromatic effects.",
            "PBRT's last thickness 0 means PBRT focuses the film itself: the sensor is placed "
            f"at the paraxial back focal distance at the d line, {p.bfl:.3f} mm behind the "
            "last vertex.",
            "Semi-diameters are half the table's aperture diameters. Uncoated: the source "
            f"gives no coatings. Film 36 x 24 mm; sensor semi-diameter {num(FILM_HALF_DIAGONAL)} "
            "mm (the film's half diagonal).",
        ]
        notes += [n for n in (aperture_note(lens, p),) if n]
        lens.notes = notes
        out.append((stem, lens))
    return out


def cooke_triplet() -> tuple[str, Lens]:
    file = "zmx_optiland_cooke_triplet_lens1.csv"
    header, _ = read_csv(CSV_DIR / file)
    lens = from_zemax_csv(CSV_DIR / file, "cooke-triplet-25mm")
    enpd = float(header_value(header, "ENPD"))
    max_field = round(max(float(v) for v in header_value(header, "YFLN").split()), 6)
    margin = 1.05
    marginal, chief = ray_heights(lens, enpd / 2, max_field)
    stop = stop_index(lens)
    for i, s in enumerate(lens.surfaces[:-1]):
        if i == stop:
            s.sd = abs(marginal[i])
        else:
            s.sd = math.ceil((abs(marginal[i]) + abs(chief[i])) * margin * 10) / 10
    p = paraxial(lens)
    lens.fnumber = round(p.efl / enpd, 3)
    lens.fov = 2 * max_field
    lens.source = (
        "Cooke triplet N-SK16/N-SF2/N-LAK9, github.com/HarrisonKramer/optiland "
        "tests/zemax_files/lens1.zmx @1fcb387 (MIT), via lenses/sources/csv/" + file + "."
    )
    lens.notes = [
        efl_note(lens, p) + " The source states no focal length.",
        f"The Zemax file has no semi-diameters. The stop's is set so that the entrance pupil "
        f"diameter is the file's ENPD {enpd:.3f} mm (paraxial f/{p.efl / enpd:.3f}; the "
        f"f-number is EFL/ENPD). The others are the paraxial marginal ray height at that "
        f"pupil plus the paraxial chief ray height at the file's largest field, "
        f"{num(max_field)} degrees, times {margin}, rounded up to 0.1 mm.",
        "Catalogue glasses by name (GCAT SCHOTT). The object surface is skipped; the sensor "
        f"is at the file's image distance {lens.surfaces[-2].thickness:.3f} mm (paraxial back "
        f"focal distance {p.bfl:.3f} mm).",
        "Uncoated: the source gives no coatings. Film 36 x 24 mm by convention, far wider "
        f"than the design field (image circle radius about "
        f"{abs(p.efl) * math.tan(math.radians(max_field)):.1f} mm).",
    ]
    return "cooke-triplet-25mm", lens


def laikin_wide_angle() -> tuple[str, Lens]:
    file = "zmx_optiland_laikin_100deg_wide_angle.csv"
    header, rows = read_csv(CSV_DIR / file)
    stem = "laikin-wide-angle-100deg"
    lens = from_zemax_csv(CSV_DIR / file, stem)
    unit = header_value(header, "UNIT").split()[0]
    factor = 25.4 if unit == "IN" else 1.0
    enpd = float(header_value(header, "ENPD")) * factor
    max_field = round(max(float(v) for v in header_value(header, "YFLN").split()), 6)
    p = paraxial(lens)
    lens.fnumber = round(p.efl / enpd, 3)
    lens.fov = 2 * max_field
    image_sd = float(rows[-1]["semi_diameter_mm"])
    stop_sd = lens.surfaces[stop_index(lens)].sd
    lens.source = (
        "100 deg Laikin wide angle lens (M. Laikin, Lens Design), "
        "github.com/HarrisonKramer/optiland tests/zemax_files/"
        "circular_aperture_example_with_aperture.zmx @1fcb387 (MIT), via lenses/sources/csv/"
        + file + "."
    )
    lens.notes = [
        efl_note(lens, p) + " The source states no focal length.",
        f"Lengths converted from inches (x {num(factor)}). The f-number is EFL/ENPD with the "
        f"file's ENPD {enpd:.3f} mm; the stop semi-diameter {stop_sd:.3f} mm is the file's "
        f"(wide open: paraxial f/{p.f_open:.3f}).",
        "Dummy surfaces dropped: the object surface; the flat air surface 1 in front of the "
        "first lens with its 12.7 mm gap (the object is at infinity, so nothing changes); "
        "the flat air surface 10, whose 23.774 mm are added to the gap before it.",
        "Catalogue glasses by name (GCAT SCHOTT: N-SK4, SF1). The sensor is at the file's "
        f"image distance {lens.surfaces[-2].thickness:.3f} mm (paraxial back focal distance "
        f"{p.bfl:.3f} mm).",
        "Uncoated: the coatings named in the Zemax file are not carried over. Film 36 x 24 "
        f"mm by convention; the Zemax image semi-diameter is {image_sd:.2f} mm, the sensor "
        f"semi-diameter here {num(FILM_HALF_DIAGONAL)} mm (the film's half diagonal).",
    ]
    return stem, lens


def heliar_lff() -> tuple[str, Lens]:
    file = "lff_heliar_tronnier.csv"
    header, _ = read_csv(CSV_DIR / file)
    stem = "heliar-tronnier-lff"
    lens = from_lff_csv(CSV_DIR / file, stem)
    lens.fnumber = float(header_value(header, "fnumber"))
    lens.efl = float(header_value(header, "effectiveFocalLength"))
    lens.fov = float(header_value(header, "fieldOfView"))
    lens.film = tuple(float(header_value(header, k)) for k in ("filmWidth", "filmHeight"))
    p = paraxial(lens)
    lens.source = (
        "LensFlareFramework, github.com/bodonyiandi94/LensFlareFramework "
        "Assets/Lenses/heliar-tronnier.xml @4136459 (BSD-style licence), via "
        f"lenses/sources/csv/{file}; the Heliar-Tronnier of Hullin et al. 2011's test set."
    )
    lens.notes = [
        "Design: US 2,645,156 (A. W. Tronnier / Voigtlaender, Color-Heliar type), scaled to "
        "EFL 100; the same prescription as heliar-tronnier.xml with LensFlareFramework's "
        "settings (f/16, film 53 x 40.2 mm).",
        efl_note(lens, p),
        "LensFlareFramework's XML heights are multiplied by its heightMultiplier 0.5 when "
        "loaded: the semi-diameters here are those halved heights; the sensor's 24 mm is "
        "used as given.",
        OLF_COATING_NOTE.replace("OpenLensFlare", "LensFlareFramework"),
    ]
    notes = [n for n in (aperture_note(lens, p), focus_note(p)) if n]
    lens.notes += notes
    return stem, lens


def readme_table(entries: list[tuple[str, Lens]]) -> str:
    rows = [
        "| file | lens | source (licence) | stated EFL | paraxial EFL (d line) | f-number |",
        "|---|---|---|---|---|---|",
    ]
    for stem, lens in entries:
        p = paraxial(lens)
        stated = f"{num(lens.efl)} mm" if lens.efl is not None else "—"
        fno = f"f/{num(lens.fnumber)}" if lens.fnumber is not None else "wide open"
        rows.append(
            f"| `{stem}.xml` | {DESCRIPTIONS[stem]} | {SOURCES[stem]} | {stated} "
            f"| {p.efl:.2f} mm | {fno} |"
        )
    return "\n".join(rows)


DESCRIPTIONS = {
    "canon-zoom-long": "Canon EF 70-200 f/2.8L type zoom, long end",
    "canon-zoom-mid": "Canon EF 70-200 f/2.8L type zoom, middle",
    "canon-zoom-short": "Canon EF 70-200 f/2.8L type zoom, short end",
    "heliar-tronnier": "Voigtländer Color-Heliar type (Tronnier), 5 elements",
    "itoh-zoom-long": "Itoh zoom (US 4,196,968), long end",
    "itoh-zoom-mid": "Itoh zoom (US 4,196,968), middle",
    "itoh-zoom-short": "Itoh zoom (US 4,196,968), short end",
    "kreitzer-tele": "Kreitzer telephoto (US 4,359,272), dimensions ×4",
    "lensbaby": "generic three-surface lens (n 1.5, V 50 placeholders)",
    "nikon-zoom-long": "Nikon 80-200 f/2.8 type zoom, long end",
    "nikon-zoom-mid": "Nikon 80-200 f/2.8 type zoom, middle",
    "nikon-zoom-short": "Nikon 80-200 f/2.8 type zoom, short end",
    "double-gauss-50mm": "double Gauss 50 mm f/2 (Tronnier)",
    "wide-22mm": "wide angle 22 mm (Nakamura)",
    "telephoto-250mm": "telephoto 250 mm",
    "fisheye-10mm": "fisheye 10 mm f/4, 155.9° (Muller)",
    "cooke-triplet-25mm": "Cooke triplet 25 mm f/3",
    "laikin-wide-angle-100deg": "Laikin 100° wide angle, 18.5 mm",
    "heliar-tronnier-lff": "Heliar-Tronnier with LensFlareFramework's settings",
}

SOURCES = {
    **{
        k: "OpenLensFlare (BSD-2-Clause)"
        for k in [
            "canon-zoom-long", "canon-zoom-mid", "canon-zoom-short", "heliar-tronnier",
            "itoh-zoom-long", "itoh-zoom-mid", "itoh-zoom-short", "kreitzer-tele", "lensbaby",
            "nikon-zoom-long", "nikon-zoom-mid", "nikon-zoom-short",
        ]
    },
    **{
        k: "pbrt-v4-scenes (no licence stated; patent data)"
        for k in ["double-gauss-50mm", "wide-22mm", "telephoto-250mm", "fisheye-10mm"]
    },
    "cooke-triplet-25mm": "optiland test data (MIT)",
    "laikin-wide-angle-100deg": "optiland test data (MIT)",
    "heliar-tronnier-lff": "LensFlareFramework (BSD-style)",
}

TABLE_BEGIN = "<!-- lens table: generated by sources/convert.py -->"
TABLE_END = "<!-- end of lens table -->"


def main():
    systems = systems_table()
    entries = olf_lenses(systems) + pbrt_lenses()
    entries += [cooke_triplet(), laikin_wide_angle(), heliar_lff()]
    for stem, lens in entries:
        s = lens.surfaces
        assert s[-1].kind == "sensor" and all(x.kind != "sensor" for x in s[:-1]), stem
        stop_index(lens)
        (LENSES / f"{stem}.xml").write_text(to_xml(lens))
        p = paraxial(lens)
        print(f"{stem:28} EFL {p.efl:9.3f}  BFL {p.bfl:8.3f}  open f/{p.f_open:.3f}  "
              f"focus error {p.focus_error:+.3f}")
    readme = LENSES / "README.md"
    if readme.exists():
        text = readme.read_text()
        if TABLE_BEGIN in text and TABLE_END in text:
            head, rest = text.split(TABLE_BEGIN, 1)
            _, tail = rest.split(TABLE_END, 1)
            table = readme_table(entries)
            readme.write_text(f"{head}{TABLE_BEGIN}\n{table}\n{TABLE_END}{tail}")


if __name__ == "__main__":
    main()
