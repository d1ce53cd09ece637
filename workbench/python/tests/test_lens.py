"""flarebench.Lens: the paraxial data `flarebench info` prints, and errors as exceptions."""

import pytest

import flarebench

# The keys of `flarebench info --json` that are Lens properties of the same name and value.
PARAXIAL_KEYS = [
    "wavelength_nm",
    "efl_mm",
    "bfl_mm",
    "ffl_mm",
    "entrance_pupil_z_mm",
    "entrance_pupil_diameter_mm",
    "exit_pupil_z_mm",
    "exit_pupil_diameter_mm",
    "f_number",
    "open_f_number",
    "stop_semi_diameter_mm",
    "stop_full_semi_diameter_mm",
    "total_track_mm",
    "focus_error_mm",
    "petzval_sum",
]


@pytest.mark.parametrize("name", ["heliar-tronnier", "double-gauss-50mm"])
def test_paraxial_data_equals_flarebench_info_exactly(name, cli_info):
    info = cli_info(name)
    lens = flarebench.Lens(name)
    for key in PARAXIAL_KEYS:
        assert getattr(lens, key) == info[key], key
    assert lens.paraxial() == {k: info[k] for k in PARAXIAL_KEYS}
    assert lens.name == info["name"]
    assert lens.stated_efl_mm == info["stated_efl_mm"]
    assert lens.stated_f_number == info["stated_f_number"]
    assert lens.film_width_mm == info["film_width_mm"]
    assert lens.film_height_mm == info["film_height_mm"]
    assert lens.path.resolve() == type(lens.path)(info["file"]).resolve()


@pytest.mark.parametrize("name", ["heliar-tronnier", "double-gauss-50mm"])
def test_counts_follow_the_prescription_of_flarebench_info(name, cli_info):
    surfaces = cli_info(name)["surfaces"]
    lens = flarebench.Lens(name)
    assert lens.surface_count == len(surfaces)
    assert lens.stop_index == [s["kind"] for s in surfaces].index("stop")
    # One ghost per pair of reflecting surfaces: every surface but the stop and the sensor.
    n = sum(s["kind"] not in ("stop", "sensor") for s in surfaces)
    assert lens.ghost_count == n * (n - 1) // 2


def test_the_heliar_has_the_values_its_file_and_the_readme_state():
    lens = flarebench.Lens("heliar-tronnier")
    assert (lens.surface_count, lens.stop_index, lens.ghost_count) == (10, 5, 28)
    # 99.24 mm at the d line (lenses/heliar-tronnier.xml notes; the file states 100).
    assert lens.efl_mm == pytest.approx(99.2358, abs=1e-4)
    assert lens.stated_efl_mm == 100.0
    assert "heliar-tronnier" in repr(lens)


def test_a_lens_is_read_from_a_path_as_from_its_name():
    by_name = flarebench.Lens("heliar-tronnier")
    by_path = flarebench.Lens(by_name.path)
    assert by_path.paraxial() == by_name.paraxial()


def test_the_digital_sensor_stack_adds_its_plates_as_info_does(cli):
    import json

    info = json.loads(cli("info", "heliar-tronnier", "--json", "--sensor-stack", "digital"))
    lens = flarebench.Lens("heliar-tronnier", sensor_stack="digital")
    assert lens.surface_count == len(info["surfaces"])
    assert lens.surface_count > flarebench.Lens("heliar-tronnier").surface_count
    assert lens.efl_mm == info["efl_mm"]


def test_an_unknown_lens_raises_file_not_found_with_the_cli_message():
    with pytest.raises(FileNotFoundError, match="no lens file `no-such-lens-xyz`"):
        flarebench.Lens("no-such-lens-xyz")


def test_a_bad_lens_file_raises_value_error_naming_file_line_and_field(tmp_path):
    good = flarebench.Lens("heliar-tronnier").path.read_text()
    lines = good.splitlines()
    # The first <thickness> made unreadable; its 1-based line number.
    line = next(i for i, l in enumerate(lines) if "<thickness>" in l)
    lines[line] = lines[line].replace("7.7", "seven")
    bad = tmp_path / "bad.xml"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError) as e:
        flarebench.Lens(str(bad))
    message = str(e.value)
    assert f"{bad}:{line + 1}:" in message
    assert "thickness" in message


def test_a_bad_sensor_stack_raises_value_error():
    with pytest.raises(ValueError, match="sensor_stack `cmos`"):
        flarebench.Lens("heliar-tronnier", sensor_stack="cmos")
