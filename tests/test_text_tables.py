"""A lab's text files read as they are (posture_id/text_table.py): tab, ';' or ','
separated, decimal commas, title and comment lines, trailing delimiters, UTF-8 (with or
without a byte-order mark) or Latin-1, units in the header; every refusal one line naming
the file, the line as in the file and the column. Then the same files through
Recording.from_lab_csv and the command line, time in milliseconds included."""

from __future__ import annotations

import json
import re
import time

import numpy as np
import pytest

from posture_id.cli import main
from posture_id.errors import RecordingError, StimulusError
from posture_id.fileio import read_numeric_csv
from posture_id.recording import AngleUnit, Recording, RecordingColumns, TimeUnit
from posture_id.simulation import simulate
from posture_id.text_table import TextTable, read_text_table, split_unit

#: The issue's force-plate export: a title line above the header, tab-separated, decimal
#: commas, time in ms, units in brackets, a trailing tab after the title.
EXPORT = ("Posturography trial export - subject 07, eyes closed\t\n"
          "Time [ms]\tPlatform [°]\tCOP AP [mm]\tFz [N]\n"
          "0\t0,000\t12,31\t686,2\n"
          "10\t0,000\t12,29\t686,4\n"
          "20\t0,015\t12,25\t686,9\n")


def _read(tmp_path, text: str | bytes, name: str = "lab.txt") -> TextTable:
    path = tmp_path / name
    if isinstance(text, str):
        path.write_text(text, encoding="utf-8")
    else:
        path.write_bytes(text)
    return read_text_table(path, RecordingError, "recording")


def _refused(tmp_path, text: str | bytes, match: str, name: str = "lab.txt") -> str:
    with pytest.raises(RecordingError, match=match) as caught:
        _read(tmp_path, text, name)
    message = str(caught.value)
    assert "\n" not in message and message.startswith(str(tmp_path / name)), message
    return message


# ------------------------------------------------------------------ the reader
def test_the_force_plate_export_in_latin_1(tmp_path):
    table = _read(tmp_path, EXPORT.encode("latin-1"))
    assert table.header == ("Time [ms]", "Platform [°]", "COP AP [mm]", "Fz [N]")
    assert table.names_without_units == ("Time", "Platform", "COP AP", "Fz")
    assert table.units == ("ms", "deg", "mm", "N")
    np.testing.assert_array_equal(table.values, [[0, 0, 12.31, 686.2], [10, 0, 12.29, 686.4],
                                                 [20, 0.015, 12.25, 686.9]])
    assert (table.delimiter, table.decimal, table.encoding) == ("\t", ",", "cp1252")
    assert (table.header_line, table.first_data_line) == (2, 3)
    assert table.row_lines.tolist() == [3, 4, 5]
    said = " ".join(table.notices)
    assert "not UTF-8" in said and "cp1252" in said and "line 1 above the header" in said
    assert "decimal commas" in said


def test_a_windows_export_with_a_dash_in_its_title(tmp_path):
    text = EXPORT.replace(" - ", " — ")
    table = _read(tmp_path, text.encode("cp1252"))
    assert table.encoding == "cp1252" and table.unit_of("Platform") == "deg"
    assert table.values.shape == (3, 4)


def test_semicolons_and_decimal_commas_with_german_headers(tmp_path):
    table = _read(tmp_path, "Zeit [ms];Neigung [°];Hüfte [deg];COM (rad)\n"
                            "0;0,5;-1,25;0,001\n"
                            "10;-0,5;1,5e-1;,002\n")
    assert table.delimiter == ";" and table.decimal == "," and table.encoding == "utf-8"
    assert table.units == ("ms", "deg", "deg", "rad")
    np.testing.assert_array_equal(table.values, [[0, 0.5, -1.25, 0.001],
                                                 [10, -0.5, 0.15, 0.002]])
    np.testing.assert_array_equal(table.column("Hüfte"), [-1.25, 0.15])
    assert table.notices == (f"{tmp_path / 'lab.txt'}: decimal commas",)


def test_commas_and_points_with_a_comment_block(tmp_path):
    table = _read(tmp_path, "# exported by PosturoLab 3.2\n"
                            "# subject 07, 1.75 m, 70 kg\n"
                            "% sampling: 100 Hz\n"
                            "\n"
                            "Temps (s),Inclinaison (deg),COM\n"
                            "0.00,0.5,1.5\n"
                            "\n"
                            "# a pause in the export\n"
                            "0.01,0.25,-2e-3\n")
    assert (table.delimiter, table.decimal) == (",", ".")
    assert table.header == ("Temps (s)", "Inclinaison (deg)", "COM")
    assert table.units == ("s", "deg", None)
    assert (table.header_line, table.row_lines.tolist()) == (5, [6, 9])
    np.testing.assert_array_equal(table.values, [[0, 0.5, 1.5], [0.01, 0.25, -0.002]])
    assert table.notices == ()  # comments and blank lines are no news


@pytest.mark.parametrize("delimiter", ["\t", ";", ","])
def test_a_trailing_delimiter_is_left_out(tmp_path, delimiter):
    decimal = "," if delimiter != "," else "."
    lines = ["t [s]", "tilt [deg]", "hip [deg]"], ["0", "0.5", "1"], ["0.02", "0.25", "2"]
    text = "".join(delimiter.join(c.replace(".", decimal) for c in line) + delimiter + "\n"
                   for line in lines)
    table = _read(tmp_path, text)
    assert table.header == ("t [s]", "tilt [deg]", "hip [deg]")
    np.testing.assert_array_equal(table.values, [[0, 0.5, 1], [0.02, 0.25, 2]])
    assert any("trailing" in n for n in table.notices)
    # an empty last cell without a trailing delimiter is a missing number, not one
    _refused(tmp_path, "t,tilt\n0,1\n1,\n", r"line 3, column 'tilt': not a number \(''\)")
    # some lines with a trailing delimiter, some without: each read for what it is
    mixed = _read(tmp_path, "t\tx\t\n0\t1\t\n1\t2\n")
    np.testing.assert_array_equal(mixed.values, [[0, 1], [1, 2]])


def test_a_utf8_byte_order_mark(tmp_path):
    table = _read(tmp_path, "\ufeffTime [s]\tPlatform [deg]\n0\t1,5\n0,01\t2\n".encode())
    assert table.encoding == "utf-8-sig" and table.header[0] == "Time [s]"
    np.testing.assert_array_equal(table.values, [[0, 1.5], [0.01, 2]])
    utf16 = _read(tmp_path, "Time [s];Tilt [°]\r\n0;1,5\r\n".encode("utf-16"))
    assert utf16.encoding == "utf-16" and utf16.units == ("s", "deg")


def test_a_column_by_either_spelling_and_its_unit(tmp_path):
    table = _read(tmp_path, EXPORT)
    for name in ("COP AP [mm]", "COP AP", " COP AP "):
        np.testing.assert_array_equal(table.column(name), [12.31, 12.29, 12.25])
        assert table.unit_of(name) == "mm" and table.has(name)
    assert table.unit_of("Fz") == "N" and table.unit_of("Time [ms]") == "ms"
    assert not table.has("COP ML") and not table.has("COPAP")
    with pytest.raises(RecordingError, match=r"lab.txt: no column 'COP ML', 'Fx' \(the header "
                                             r"is Time \[ms\],Platform \[°\],COP AP \[mm\],"
                                             r"Fz \[N\]\)"):
        table.require(["COP AP", "COP ML", "Fx"])
    twice = _read(tmp_path, "angle [deg],angle [rad]\n1,2\n")
    assert twice.column("angle [rad]")[0] == 2
    with pytest.raises(RecordingError, match="'angle' is named twice"):
        twice.column("angle")


@pytest.mark.parametrize(("name", "split"), [
    ("COP AP [mm]", ("COP AP", "mm")), ("Neigung [°]", ("Neigung", "deg")),
    ("Zeit[ms]", ("Zeit", "ms")), ("Fz (N)", ("Fz", "N")), ("tilt (rad)", ("tilt", "rad")),
    ("COP (AP)", ("COP (AP)", None)), ("Fz [kgf]", ("Fz", "kgf")), ("time_s", ("time_s", None)),
    ("[ms]", ("[ms]", None)), ("Weg [cm]", ("Weg", "cm")), ("x (m)", ("x", "m")),
])
def test_units_read_from_the_header(name, split):
    assert split_unit(name) == split


def test_a_bad_cell_is_named_by_its_line_in_the_file(tmp_path):
    text = EXPORT.replace("10\t0,000\t12,29", "10\t0,000\tn/a")
    _refused(tmp_path, text, r"lab.txt: line 4, column 'COP AP \[mm\]': not a number "
                             r"\('n/a'\)$")
    _refused(tmp_path, EXPORT.replace("686,9", "inf"),
             r"line 5, column 'Fz \[N\]': inf is not a finite number")
    # a bad first data row: the header is still the header
    _refused(tmp_path, "time_s,tilt_deg\n0,abc\n1,2\n", r"line 2, column 'tilt_deg'")
    # after comments and a blank line the numbering is still the file's
    _refused(tmp_path, "# a\n\nt;x\n0;1\n# b\n1;x\n",
             r"line 6, column 'x': not a number \('x'\)")


def test_an_inconsistent_row_is_named(tmp_path):
    _refused(tmp_path, EXPORT.replace("686,4", "686,4\t1"),
             r"lab.txt: line 4: 5 fields, the header \(line 2\) has 4$")
    _refused(tmp_path, "a,b\n1,2\n3,4,5\n", r"line 3: 3 fields, the header has 2$")
    _refused(tmp_path, EXPORT.replace("20\t0,015\t12,25\t686,9", "20\t0,015"),
             r"line 5: 2 fields, the header \(line 2\) has 4")


def test_files_that_are_not_tables_are_refused(tmp_path):
    _refused(tmp_path, "", "empty file, expected a recording")
    _refused(tmp_path, "# only\n% comments\n\n", "empty file")
    _refused(tmp_path, "Title\nTime [s];Tilt [deg]\n", "a header and no data rows")
    _refused(tmp_path, "0,1\n1,2\n", "line 1 holds numbers where the header should be")
    _refused(tmp_path, b"t,x\n0,\x00\n", r"binary data \(byte 6 is NUL\)")
    _refused(tmp_path, "t;x\n0;1,5\n1;2.5\n",
             r"both decimal commas \(line 2, column 'x' \('1,5'\)\) and decimal points "
             r"\(line 3, column 'x' \('2.5'\)\): the decimal mark is ambiguous")
    _refused(tmp_path, "t\tx\n0\t1.234,5\n", "the decimal mark is ambiguous")


def test_quoted_cells(tmp_path):
    table = _read(tmp_path, '"Time [ms]";"Tilt [deg]"\n"0";"1,5"\n"10";"2"\n')
    assert table.header == ("Time [ms]", "Tilt [deg]")
    np.testing.assert_array_equal(table.values, [[0, 1.5], [10, 2]])


def test_todays_files_read_as_before(tmp_path):
    """The standard header, comma and point: header and values as float() reads them,
    whichever path read them (numpy's, or cell by cell for what numpy does not take)."""
    rng = np.random.default_rng(3)
    values = rng.normal(size=(50, 3))
    path = tmp_path / "rec.csv"
    path.write_text("time_s,tilt_deg,shank_deg\n" + "".join(
        ",".join(repr(float(x)) for x in row) + "\n" for row in values))
    header, read = read_numeric_csv(path, RecordingError, "recording")
    assert header == ["time_s", "tilt_deg", "shank_deg"]
    np.testing.assert_array_equal(read, values)
    path.write_text("x, y \n 1_0 , 2\n3,4\n")  # float() takes 1_0, numpy does not
    assert read_numeric_csv(path, StimulusError, "tilt file") == (["x", "y"], pytest.approx(
        np.array([[10.0, 2.0], [3.0, 4.0]])))


def test_a_large_export_reads_fast(tmp_path):
    rows = 18_000
    rng = np.random.default_rng(4)
    data = np.column_stack([10 * np.arange(rows), rng.normal(size=(rows, 3))])
    path = tmp_path / "big.txt"
    path.write_bytes(("Export\t\nTime [ms]\tPlatform [deg]\tCOP AP [mm]\tFz [N]\n" + "".join(
        f"{int(r[0])}\t{r[1]:.4f}\t{r[2]:.3f}\t{r[3]:.2f}\n".replace(".", ",")
        for r in data)).encode("latin-1"))
    start = time.perf_counter()
    table = read_text_table(path, RecordingError, "recording")
    took = time.perf_counter() - start
    assert table.values.shape == (rows, 4)
    np.testing.assert_allclose(table.values[:, 1], data[:, 1], atol=5e-5)
    assert took < 1.0, took  # about 30 ms here; cell by cell would take several times more


# ------------------------------------------------------------------ recordings
def _export(path, t_s, tilt_deg, com_deg, header_time="Time [ms]", encoding="latin-1"):
    """The lab's export of a COM-only recording: title, tab, decimal commas, ms."""
    body = "".join(f"{1000 * t:.10g}\t{a:.12g}\t{c:.12g}\t686,2\n".replace(".", ",")
                   for t, a, c in zip(t_s, tilt_deg, com_deg, strict=True))
    path.write_bytes((f"Posturography trial export - subject 07\t\n{header_time}\t"
                      "Platform [deg]\tCOM sway [°]\tFz [N]\n" + body).encode(encoding))


def test_a_recording_in_milliseconds(tmp_path):
    t = np.arange(200) / 100.0
    tilt, com = np.sin(t), 0.5 * np.cos(t)
    path = tmp_path / "lab.txt"
    _export(path, t, tilt, com)
    columns = RecordingColumns(time="Time", tilt="Platform", angles=("COM sway",))
    rec = Recording.read(path, None, None, columns)
    np.testing.assert_allclose(rec.time, t, atol=1e-12)
    np.testing.assert_allclose(np.degrees(rec.theta[:, 0]), com, rtol=1e-10)
    assert rec.segments == ("COM sway",)
    assert Recording.read(path, None, None, RecordingColumns(
        time="Time [ms]", tilt="Platform [deg]", angles=("COM sway [°]",),
        time_unit=TimeUnit.MILLISECONDS, unit=AngleUnit.DEGREES)).time[-1] == pytest.approx(1.99)
    with pytest.raises(RecordingError, match=r"lab.txt: column 'Time \[ms\]' is in ms by its "
                                             r"header, but the time unit given is s "
                                             r"\(--time-units s\)"):
        Recording.from_lab_csv(path, RecordingColumns(
            time="Time", tilt="Platform", angles=("COM sway",), time_unit=TimeUnit.SECONDS),
            ("body",))
    with pytest.raises(RecordingError, match=r"column 'COM sway \[°\]' is in deg by its "
                                             r"header, but the angle unit given is rad"):
        Recording.from_lab_csv(path, RecordingColumns(
            time="Time", tilt=None, angles=("COM sway",), unit=AngleUnit.RADIANS),
            ("body",), np.sin)
    with pytest.raises(RecordingError, match=r"column 'Fz \[N\]' is in N by its header; the "
                                             "tilt and angle columns must be angles"):
        Recording.from_lab_csv(path, RecordingColumns(
            time="Time", tilt="Platform", angles=("Fz",)), ("body",))
    # no unit in the header: milliseconds said by the columns, or refused with the flag
    _export(path, t, tilt, com, header_time="Time")
    ms = RecordingColumns(time="Time", tilt="Platform", angles=("COM sway",),
                          time_unit=TimeUnit.MILLISECONDS)
    np.testing.assert_allclose(Recording.from_lab_csv(path, ms, ("body",)).time, t, atol=1e-12)
    with pytest.raises(RecordingError, match=r"column 'Time': the median sample interval is "
                                             r"10 s .*is the time in milliseconds\? give "
                                             "--time-units ms"):
        Recording.from_lab_csv(path, RecordingColumns(time="Time", tilt="Platform",
                                                      angles=("COM sway",)), ("body",))


def test_the_angle_unit_from_the_header(tmp_path):
    t = np.arange(100) / 50.0
    path = tmp_path / "rad.csv"
    path.write_text("Time [s],Tilt [rad],Hip [rad]\n" + "".join(
        f"{x:.17g},{0.01 * np.sin(x):.17g},{0.001 * np.cos(x):.17g}\n" for x in t))
    rec = Recording.from_lab_csv(path, RecordingColumns(time="Time", tilt="Tilt",
                                                        angles=("Hip",)), ("body",))
    np.testing.assert_allclose(rec.theta[:, 0], 0.001 * np.cos(t))  # not taken for degrees
    np.testing.assert_allclose(rec.tilt, 0.01 * np.sin(t))
    path.write_text("Time [s],Tilt [deg],Hip\n" + "".join(
        f"{x:.17g},{np.sin(x):.17g},{0.001 * np.cos(x):.17g}\n" for x in t))
    columns = RecordingColumns(time="Time", tilt="Tilt", angles=("Hip",))
    with pytest.raises(RecordingError, match=r"look like radians: give their unit \(--units "
                                             r"rad\)"):
        Recording.from_lab_csv(path, columns, ("body",))
    with pytest.raises(RecordingError, match="the angle unit given is rad"):
        Recording.from_lab_csv(path, RecordingColumns(time="Time", tilt="Tilt", angles=("Hip",),
                                                      unit=AngleUnit.RADIANS), ("body",))


def test_columns_refuse_a_time_unit_without_a_time_column():
    with pytest.raises(RecordingError, match="a time unit without a time column"):
        RecordingColumns(time=None, tilt=None, angles=("x",), sample_rate_hz=100.0,
                         time_unit=TimeUnit.MILLISECONDS)
    with pytest.raises(RecordingError, match="time_unit must be a TimeUnit"):
        RecordingColumns(angles=("x",), time_unit="ms")


# ------------------------------------------------------------------ the command line
@pytest.fixture(scope="module")
def sway(tip):
    recording = simulate(tip).to_recording()
    return recording, np.degrees(tip.com_angles(recording.theta)[:, 0])


def test_a_lab_export_end_to_end(tmp_path, sway, capsys):
    """The issue's export through ``posture-id frf``: the same FRF as the same sway in
    posture_id's own columns."""
    recording, com = sway
    lab = tmp_path / "trial 07.txt"
    _export(lab, recording.time, np.degrees(recording.tilt), com)
    own = tmp_path / "com.csv"
    own.write_text("time_s,tilt_deg,com_deg\n" + "".join(
        f"{t:.6f},{np.degrees(a):.12g},{c:.12g}\n"
        for t, a, c in zip(recording.time, recording.tilt, com, strict=True)))
    assert main(["frf", str(own), "--bands", "12", "--out", str(tmp_path / "own.json")]) == 0
    assert main(["frf", str(lab), "--angle-columns", "COM sway", "--time-column", "Time",
                 "--tilt-column", "Platform", "--time-units", "ms", "--bands", "12",
                 "--out", str(tmp_path / "lab.json")]) == 0
    expected = json.loads((tmp_path / "own.json").read_text())["channels"]["com"]
    got = json.loads((tmp_path / "lab.json").read_text())["channels"]["COM sway"]
    np.testing.assert_allclose(got["gain"], expected["gain"], rtol=1e-6)
    np.testing.assert_allclose(got["phase_deg"], expected["phase_deg"], atol=1e-4)
    capsys.readouterr()
    # --time-units contradicting the header: refused in one line naming file, column, units
    assert main(["frf", str(lab), "--angle-columns", "COM sway", "--time-column", "Time",
                 "--tilt-column", "Platform", "--time-units", "s",
                 "--out", str(tmp_path / "no.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(lab) in err, err
    assert "column 'Time [ms]' is in ms by its header, but the time unit given is s" in err
    assert not (tmp_path / "no.json").exists()
    assert main(["frf", str(lab), "--angle-columns", "COM sway", "--time-column", "Time",
                 "--tilt-column", "Platform", "--units", "rad",
                 "--out", str(tmp_path / "no.json")]) == 2
    err = capsys.readouterr().err
    assert "column 'Platform [deg]' is in deg by its header, but the angle unit given is " \
           "rad (--units rad)" in err, err


def test_the_unit_flags_go_with_the_columns(tmp_path, capsys):
    path = tmp_path / "rec.csv"
    path.write_text("time_s,tilt_deg,shank_deg\n0,0,1\n0.02,1,2\n")
    for flags, said in ((["--time-units", "ms"], "--time-units goes with --angle-columns"),
                        (["--units", "rad", "--time-units", "ms"],
                         "--units and --time-units go with --angle-columns")):
        assert main(["frf", str(path), *flags, "--out", str(tmp_path / "f.json")]) == 2
        assert said in capsys.readouterr().err


@pytest.mark.parametrize("codec, order", [("utf-16-le", "little-endian"),
                                          ("utf-16-be", "big-endian")])
def test_utf16_without_a_byte_order_mark_is_read_and_said(tmp_path, codec, order):
    """A Windows export in UTF-16 with no byte-order mark: one byte of every character
    pair NUL. Read as the same table, said; a file with other NUL bytes stays binary."""
    table = _read(tmp_path, EXPORT.encode(codec))
    same = _read(tmp_path, EXPORT, "utf8.txt")
    np.testing.assert_array_equal(table.values, same.values)
    assert table.header == same.header and table.encoding == codec
    assert any(f"read as UTF-16 ({order}, no byte-order mark)" in n for n in table.notices)
    _refused(tmp_path, EXPORT.encode(codec)[:-1], "binary data")  # an odd number of bytes
    _refused(tmp_path, b"t,x\n" + b"0,1\x00\x00\x002\n" * 4, "binary data")


def test_a_recordings_reading_notices_reach_its_trial(tmp_path):
    """What the reader noticed (an encoding, lines skipped) is the recording's and its
    prepared trial's notice, for a lab's columns and the project's own."""
    from posture_id.bodies.body import load_body
    from posture_id.trials import prepare_trial

    recording = simulate(load_body()).to_recording()
    rows = "".join(f"{t:.3f},{np.degrees(a):.6f},{np.degrees(s):.6f}\n" for t, a, s in
                   zip(recording.time, recording.tilt, recording.theta[:, 0], strict=True))
    lab = tmp_path / "lab.csv"
    lab.write_bytes(("Messung Müller\nT,P,S\n" + rows).encode("cp1252"))
    read = Recording.read(lab, ("shank",), None, RecordingColumns("T", "P", ("S",)))
    assert any("cp1252" in n for n in read.notices)
    assert any("above the header" in n for n in read.notices)
    own = tmp_path / "own.csv"
    own.write_bytes(("time_s,tilt_deg,shank_deg\n" + rows).encode("utf-16-le"))
    trial = prepare_trial(Recording.read(own), None)
    assert any("UTF-16" in n for n in trial.notices)


def test_a_sample_rate_given_against_the_time_column_is_said(tmp_path):
    path = tmp_path / "lab.csv"
    path.write_text("T,P,S\n" + "".join(f"{k / 50:.3f},0.{k % 7},1.{k % 5}\n"
                                         for k in range(200)))
    columns = RecordingColumns("T", "P", ("S",), sample_rate_hz=100.0)
    read = Recording.read(path, ("body",), None, columns)
    assert read.sample_rate_hz == pytest.approx(100.0)
    said = " ".join(read.notices)
    assert "100" in said and "50 Hz" in said and "every frequency 2×" in said
    matching = Recording.read(path, ("body",), None, RecordingColumns(
        "T", "P", ("S",), sample_rate_hz=50.0))
    assert not any("sample rate" in n for n in matching.notices)


def test_jittered_time_stamps_are_resampled_onto_their_even_rate_and_gaps_refused(tmp_path):
    """A headset's export: 90 Hz stamps that jitter by up to 0.5 ms (a twentieth of the
    interval), each sample the sway at its own stamp. Read onto an even 90 Hz grid, said,
    the sway within 0.2 % of the even trial's; a dropped sample (a step of two intervals)
    and time that goes back are refused, naming the line."""
    rng = np.random.default_rng(4)
    n, rate = 5400, 90.0
    even = np.arange(n) / rate
    stamps = even + rng.uniform(-5e-4, 5e-4, n)
    stamps[0] = 0.0

    def sway(t):
        return 0.8 * np.sin(2 * np.pi * 0.3 * t) + 0.2 * np.sin(2 * np.pi * 1.1 * t)

    def tilt(t):
        return np.sin(2 * np.pi * 0.1 * t)

    def write(name, times):
        path = tmp_path / name
        path.write_text("Time [s];Tilt [deg];COM [deg]\n" + "".join(
            f"{t:.4f};{tilt(t):.6f};{sway(t):.6f}\n" for t in times))
        return path

    columns = RecordingColumns("Time", "Tilt", ("COM",))
    read = Recording.read(write("vr.csv", stamps), ("body",), None, columns)
    assert read.evenly_sampled() and read.sample_rate_hz == pytest.approx(rate, rel=1e-5)
    said = " ".join(read.notices)
    assert re.search(r"jitter by up to 0\.5\d? ms about an even 90 Hz clock", said)
    assert "linear interpolation" in said
    error = np.degrees(read.theta[:, 0]) - sway(read.time)
    assert np.sqrt(np.mean(error**2)) < 2e-3 * np.std(sway(read.time))
    dropped = np.delete(stamps, 2000)
    with pytest.raises(RecordingError, match=r"vr_gap.csv: line 2002: a step of 22.*gap"):
        Recording.read(write("vr_gap.csv", dropped), ("body",), None, columns)
    back = stamps.copy()
    back[3000] = back[2998]
    with pytest.raises(RecordingError, match=r"vr_back.csv: line 3002: Time does not "
                                             r"increase"):
        Recording.read(write("vr_back.csv", back), ("body",), None, columns)
