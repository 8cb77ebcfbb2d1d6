"""Tests of the Python module `engage` (apps/python/EngageModule.cpp), run by ctest.

Expected values are closed forms written next to each case. ENGAGE_BIN (set by ctest) is the
command line, whose messages the module's errors must repeat."""
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import engage

SLOT = "G21 G90 G17\nG0 X0 Y0 Z5\nG1 Z-2 F100\nG1 X30 F600\nG0 Z5\nM2\n"
BOX = "box:-10,-10,-10,40,10,0"


@pytest.fixture
def slot(tmp_path):
    p = tmp_path / "slot.ngc"
    p.write_text(SLOT)
    return str(p)


def test_cross_section_and_model_closed_forms():
    c = engage.Cutter.flat(6.0, 18.0)
    # A flat end mill at s = 3, d = 2: a 3 x 2 rectangle from the axis out to r.
    x = engage.cross_section(c, 3.0, 2.0)
    assert x["area_mm2"] == pytest.approx(6.0, rel=1e-12)
    assert x["centroid_x_mm"] == pytest.approx(1.5, rel=1e-12)
    assert x["centroid_z_mm"] == pytest.approx(1.0, rel=1e-12)
    m = engage.Model(c, stepover=3.0, depth=2.0)
    # Eq 6: s d V_f = 3 * 2 * 600.
    assert m.mrr(600.0) == pytest.approx(3600.0, rel=1e-12)
    # Concave arc of tool-centre radius 10: centroid at 10 + 1.5 (Pappus), 3600 * 11.5 / 10.
    assert m.mrr(600.0, "concave", 10.0) == pytest.approx(4140.0, rel=1e-12)
    assert m.mrr(600.0, "convex", 10.0) == pytest.approx(3600.0 * 8.5 / 10.0, rel=1e-12)
    # Inverse of Eq 6: the feed for 1800 mm^3/min is 300 mm/min.
    assert m.adaptive_feed(1800.0) == pytest.approx(300.0, rel=1e-12)
    # A ball's width at height z: sqrt(r^2 - (r - z)^2); r = 3, z = 1 -> sqrt(5).
    assert engage.Cutter.ball(6.0, 18.0).radius_at(1.0) == pytest.approx(math.sqrt(5.0))
    # Eq 17, 18, 24.
    assert engage.cutting_speed(10.0, 1000.0) == pytest.approx(math.pi * 10.0 * 1000.0)
    assert engage.tangential_acceleration(600.0, 1200.0, 1.0) == pytest.approx(
        (1200.0**2 - 600.0**2) / 3600.0 / 2.0)


def test_run_gives_numpy_columns_and_the_summary(slot, tmp_path):
    r = engage.run(program=slot, tool="flat", diameter="6mm", stock=BOX)
    steps = r.steps
    n = len(steps["step"])
    assert n > 0
    for name, column in steps.items():
        assert isinstance(column, np.ndarray), name
        assert len(column) == n, name
    # The slot: 30 x 6 stadium plus a 3 mm disc, 2 mm deep; the voxel stock is within 0.2 %
    # of a flat slot at the default voxel (D/20).
    slot_volume = (30.0 * 6.0 + math.pi * 9.0) * 2.0
    assert r.removed_mm3 == pytest.approx(slot_volume, rel=2e-3)
    assert steps["removed_mm3"].sum() == pytest.approx(r.removed_mm3, rel=1e-9)
    # Steady MRR D d F = 6 * 2 * 600 (within 0.5 %, the per-step accuracy).
    assert steps["mrr_mm3_min"].max() == pytest.approx(7200.0, rel=5e-3)
    s = r.summary
    assert s["units"] == "mm"
    assert s["removed"] == pytest.approx(r.removed_mm3, rel=1e-12)
    # steps_csv is the same table the command line writes: a header and a row per step.
    assert r.steps_csv().count("\n") == n + 1
    out = tmp_path / "out"
    r.write(str(out))
    assert json.loads((out / "summary.json").read_text())["steps"] == n
    assert (out / "stock.vdb").exists()


def test_a_program_of_three_tools_from_a_library():
    root = os.path.join(os.path.dirname(__file__), "..", "..", "data")
    r = engage.run(program=os.path.join(root, "gcode", "multitool", "three_tools.ngc"),
                   tools=os.path.join(root, "tools", "three_tools.tbl"),
                   stock="box:0,0,-10,60,40,0", stock_model="dexel")
    steps = r.steps
    by_tool = {t: steps["removed_mm3"][steps["tool"] == t].sum() for t in (1, 2, 3)}
    # T1: 6 mm flat slot 40 mm long, 2 mm deep, with its round ends: (40*6 + pi 9) * 2.
    # T3: 90 deg V-bit 1 mm deep: triangle 1 mm^2 * 40 mm + the cone pi/3 of its two ends.
    # Dexel stock: measured within 0.013 %; 0.05 % allowed.
    assert by_tool[1] == pytest.approx((40 * 6 + math.pi * 9) * 2, rel=5e-4)
    assert by_tool[3] == pytest.approx(40 + math.pi / 3, rel=5e-4)
    assert [t["number"] for t in r.summary["tools"]] == [1, 2, 3]
    assert r.summary["tool_library"]["format"] == "linuxcnc"


def test_cutting_physics_of_a_slot(slot):
    r = engage.run(program=slot, tool="flat", diameter=6, flutes=3, stock=BOX,
                   stock_model="dexel", material="aluminium-7075-t6", spindle="10000rpm",
                   helix="0deg")
    steps = r.steps
    mid = (steps["x_mm"] > 10) & (steps["x_mm"] < 20) & (steps["kind"] == "line")
    assert mid.sum() > 10
    # A slot, 2 mm deep, f_z = 600 / (10000 * 3) = 0.02 mm, Al 7075-T6's coefficients
    # (data/materials): the textbook mean forces (Altintas Eq 2.40 from 0 to pi):
    # F_feed = -N a (Krc c / 4 + Kre / pi), torque = N a R (2 Ktc c + pi Kte) / (2 pi).
    N, a, c, R = 3, 2.0, 0.02, 3.0
    Ktc, Krc, Kte, Kre = 767.01, 168.8, 27.7, 26.6
    # The slot's sides are found to 2.5 deg at the default 0.3 mm rays; the depth to a
    # slice: 3 % on the forces.
    assert np.allclose(steps["fx_N"][mid], -N * a * (Krc * c / 4 + Kre / math.pi), rtol=0.03)
    torque = N * a * R * (2 * Ktc * c + math.pi * Kte) / (2 * math.pi) / 1000
    assert np.allclose(steps["torque_Nm"][mid], torque, rtol=0.03)
    assert np.allclose(steps["power_W"][mid], torque * 2 * math.pi * 10000 / 60, rtol=0.03)
    assert np.allclose(steps["h_max_mm"][mid], c, rtol=1e-6)
    assert r.summary["physics"]["material"] == "Aluminium 7075-T6"
    # The entry and exit angles as steps.csv has them, from the feed direction in the
    # direction of rotation: a slot engages -90 to 90 deg (to 2.5 deg at the default rays).
    assert np.allclose(steps["entry_rad"][mid], -math.pi / 2, atol=math.radians(2.5))
    assert np.allclose(steps["exit_rad"][mid], math.pi / 2, atol=math.radians(2.5))
    csv = r.steps_csv().splitlines()
    header = csv[0].split(",")
    row = csv[1 + int(np.flatnonzero(mid)[0])].split(",")
    i = int(np.flatnonzero(mid)[0])
    assert float(row[header.index("entry_deg")]) == pytest.approx(
        math.degrees(steps["entry_rad"][i]), abs=1e-4)


def test_warnings_and_the_scheduled_loads(slot):
    # A 6 mm tool in 2 mm cells: 3 across, coarser than D/5; the command line warns so too.
    r = engage.run("schedule", program=slot, tool="flat", diameter=6, flutes=3, stock=BOX,
                   voxel="2mm", material="aluminium-7075-t6", spindle="10000rpm",
                   max_chip="0.01mm")
    assert any("coarse" in w for w in r.warnings)
    steps = r.steps
    mid = (steps["x_mm"] > 10) & (steps["x_mm"] < 20) & (steps["kind"] == "line")
    # Held to h_max 0.01 mm, half the programmed f_z = 0.02 mm: the scheduled chip is at most
    # the limit (1e-6: rounding) and the feed no higher than half the programmed one.
    assert np.all(steps["h_max_scheduled_mm"][mid] <= 0.01 * (1 + 1e-6))
    assert np.all(steps["feed_scheduled_mm_min"][mid] <= 300.0 * (1 + 1e-6))
    # The MRR at the scheduled feed scales with the feed (the removal per length is the same).
    assert np.allclose(steps["mrr_scheduled_mm3_min"][mid],
                       steps["mrr_mm3_min"][mid] * steps["feed_scheduled_mm_min"][mid] /
                       steps["feed_mm_min"][mid], rtol=1e-9)


@pytest.mark.parametrize("option", ["out", "quiet"])
def test_the_command_lines_own_options_are_refused(slot, option):
    with pytest.raises(engage.Error, match=option + "= is the command line's"):
        engage.run(program=slot, tool="flat", diameter=6, stock=BOX, **{option: "x"})


def test_schedule_and_cross_check(slot):
    r = engage.run("schedule", program=slot, tool="flat", diameter=6, stock=BOX,
                   target_mrr="3600mm3/min", cross_check=True)
    steps = r.steps
    assert "feed_scheduled_mm_min" in steps and "removed_voxel_mm3" in steps
    # Half the steady MRR: the steady feed halves, 600 -> 300 mm/min (a level within the
    # 5 % min-change below it).
    mid = (steps["x_mm"] > 10) & (steps["x_mm"] < 20) & (steps["feed_mm_min"] == 600.0)
    assert mid.sum() > 10
    assert np.all(steps["feed_scheduled_mm_min"][mid] <= 300.0 * 1.0001)
    assert np.all(steps["feed_scheduled_mm_min"][mid] >= 300.0 * 0.95)
    assert not steps["cross_check_differs"].any()
    assert "F" in r.refed_program


def test_read_program(slot):
    moves = engage.read_program(slot)
    assert list(moves["kind"]) == ["rapid", "line", "line", "rapid"]
    assert moves["end_x_mm"][2] == 30.0
    assert moves["feed_mm_min"][2] == 600.0


def test_options_are_the_command_lines(slot):
    names = {o["name"] for o in engage.options()}
    assert {"jerk", "rapid-feed", "material-side", "target-mrr", "stock-model"} <= names
    help_text = subprocess.run([os.environ["ENGAGE_BIN"], "schedule", "--help"],
                               capture_output=True, text=True).stdout
    for name in names:
        assert "--" + name in help_text, name


@pytest.mark.parametrize("options", [
    {"voxel": "abc"},
    {"voxle": "1"},
    {"stock_model": "cubes"},
    {"stock": "box:0,0,-10"},
    {"stock": "box:500,500,-10,560,560,0"},
])
def test_errors_are_the_command_lines(slot, tmp_path, options):
    base = {"program": slot, "tool": "flat", "diameter": "6mm", "stock": BOX}
    base.update(options)
    with pytest.raises(engage.Error) as e:
        engage.run(**base)
    args = [os.environ["ENGAGE_BIN"], "simulate", slot, "--out", str(tmp_path / "o")]
    for key, value in base.items():
        if key != "program":
            args += ["--" + key.replace("_", "-"), str(value)]
    cli = subprocess.run(args, capture_output=True, text=True)
    assert cli.returncode != 0
    if "voxle" not in options:  # the command line's own parser refuses an unknown option
        assert cli.stderr.strip() == "engage: error: " + str(e.value)


def test_fig9_example_script(tmp_path):
    script = os.path.join(os.path.dirname(__file__), "..", "..", "data", "python",
                          "fig9_corner.py")
    png = tmp_path / "fig9.png"
    run = subprocess.run([sys.executable, script, str(png)], capture_output=True, text=True,
                         env=dict(os.environ))
    assert run.returncode == 0, run.stderr
    # The corner's peak: the full slot, 2 x nominal exactly; the steps around the corner
    # sample it within a few percent.
    assert "x nominal" in run.stdout
    ratio = float(run.stdout.split("= ")[1].split(" x")[0])
    assert 1.9 < ratio <= 2.0 + 1e-3
    assert png.stat().st_size > 10000


def test_part_finds_the_slot_cut_too_deep(slot, tmp_path):
    # The part is the box below Z-1.9; SLOT cuts 2 mm deep: its floor, the stadium of
    # 30 x 6 mm and a 3 mm disc, gouges the part 0.1 mm (lines 3 and 4: the plunge and the
    # pass over it), and the stock above Z-1.9 beside the slot is left over, 1.9 mm thick.
    part = tmp_path / "part.obj"
    v = [(-10, -10, -10), (40, -10, -10), (40, 10, -10), (-10, 10, -10),
         (-10, -10, -1.9), (40, -10, -1.9), (40, 10, -1.9), (-10, 10, -1.9)]
    f = [(1, 4, 3, 2), (5, 6, 7, 8), (1, 2, 6, 5), (2, 3, 7, 6), (3, 4, 8, 7), (4, 1, 5, 8)]
    part.write_text("".join("v %g %g %g\n" % p for p in v) +
                    "".join("f %d %d %d %d\n" % q for q in f))
    r = engage.run(program=slot, tool="flat", diameter="6mm", stock=BOX, part=str(part),
                   voxel="0.25mm")
    gouges = r.summary["part"]["gouges"]
    assert gouges["count"] == 1
    g = gouges["regions"][0]
    # Depth within a tenth of the 0.25 mm cell; volume within 1 % of 0.1 x (30 x 6 + 9 pi).
    assert abs(g["depth"] - 0.1) <= 0.025
    assert g["volume"] == pytest.approx(0.1 * (30 * 6 + 9 * math.pi), rel=0.01)
    assert {line["line"] for line in g["lines"]} <= {3, 4}
    assert r.summary["part"]["leftovers"]["thickest"] == pytest.approx(1.9, abs=0.025)
