"""tools/derived_drives.py: the drives it derives (make, frames) keep the right rings, frames and labels; score maps them."""
import pathlib
import subprocess
import sys

import numpy as np
import pytest

TOOL = pathlib.Path(__file__).resolve().parents[2] / "tools" / "derived_drives.py"


def _drive(folder, frames=3, rings=4, per_ring=300):
    """A KITTI drive folder: each frame `rings` rings of `per_ring` points, azimuth rising from -pi
    to pi within a ring (as a Velodyne stores them); label = 100 x ring + frame, z = ring."""
    (folder / "velodyne").mkdir(parents=True)
    (folder / "labels").mkdir()
    az = np.linspace(-np.pi + 0.01, np.pi - 0.01, per_ring)
    for f in range(frames):
        pts, lab = [], []
        for r in range(rings):
            pts.append(np.stack([10 * np.cos(az), 10 * np.sin(az), np.full(per_ring, float(r)), np.zeros(per_ring)], 1))
            lab.append(np.full(per_ring, 100 * r + f, np.uint32))
        np.concatenate(pts).astype(np.float32).tofile(folder / "velodyne" / f"{f:06d}.bin")
        np.concatenate(lab).tofile(folder / "labels" / f"{f:06d}.label")
    (folder / "poses.txt").write_text("".join(f"1 0 0 {f} 0 1 0 0 0 0 1 0\n" for f in range(frames)))
    (folder / "calib.txt").write_text("Tr: 1 0 0 0 0 1 0 0 0 0 1 0\n")


def _read(folder, frame):
    p = np.fromfile(folder / "velodyne" / f"{frame:06d}.bin", np.float32).reshape(-1, 4)
    return p, np.fromfile(folder / "labels" / f"{frame:06d}.label", np.uint32)


def test_rings_frames_and_height_of_the_derived_drives(tmp_path):
    seq = tmp_path / "07"
    _drive(seq)
    out = tmp_path / "derived"
    r = subprocess.run([sys.executable, str(TOOL), "make", str(out), str(seq)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["07r2", "07r4", "07f2", "07lowz", "07highz"]
    for name, rings in (("07r2", [0, 2]), ("07r4", [0])):
        p, lab = _read(out / name, 1)
        assert len(p) == 300 * len(rings) == len(lab)
        assert sorted(set(lab // 100)) == rings and set(lab % 100) == {1}, "labels travel with their points"
        assert np.array_equal(p[:, 2], (lab // 100).astype(np.float32))
    assert sorted(x.name for x in (out / "07f2" / "velodyne").iterdir()) == ["000000.bin", "000001.bin"]
    assert set(_read(out / "07f2", 1)[1] % 100) == {2}, "every 2nd frame"
    assert (out / "07f2" / "poses.txt").read_text().splitlines() == ["1 0 0 0 0 1 0 0 0 0 1 0", "1 0 0 2 0 1 0 0 0 0 1 0"]
    p0, lab0 = _read(seq, 0)
    p, lab = _read(out / "07lowz", 0)
    assert np.array_equal(lab, lab0) and np.allclose(p[:, 2], p0[:, 2] + 0.5) and np.array_equal(p[:, :2], p0[:, :2])
    p, lab = _read(out / "07highz", 0)
    assert np.array_equal(lab, lab0) and np.allclose(p[:, 2], p0[:, 2] - 0.5) and np.array_equal(p[:, :2], p0[:, :2])


def test_a_frame_whose_labels_do_not_match_its_points_is_refused(tmp_path):
    seq = tmp_path / "05"
    _drive(seq, frames=1)
    np.zeros(5, np.uint32).tofile(seq / "labels" / "000000.label")
    r = subprocess.run([sys.executable, str(TOOL), "make", str(tmp_path / "d"), str(seq)], capture_output=True, text=True)
    assert r.returncode != 0 and "1200 points but 5 labels" in r.stderr
    assert not (tmp_path / "d" / "05r2").exists(), "no half drive left behind"
    again = subprocess.run([sys.executable, str(TOOL), "make", str(tmp_path / "d"), str(tmp_path / "none")], capture_output=True, text=True)
    assert again.returncode != 0 and "no velodyne" in again.stderr


def test_an_existing_derived_drive_is_not_replaced(tmp_path):
    seq = tmp_path / "00"
    _drive(seq, frames=1)
    (tmp_path / "d" / "00r2").mkdir(parents=True)
    (tmp_path / "d" / "00r2" / "keep").write_text("x")
    r = subprocess.run([sys.executable, str(TOOL), "make", str(tmp_path / "d"), str(seq)], capture_output=True, text=True)
    assert r.returncode != 0 and "exists" in r.stderr
    assert (tmp_path / "d" / "00r2" / "keep").read_text() == "x"


def test_one_frame_drives_of_the_labelled_scans_of_a_sequence(tmp_path):
    seq = tmp_path / "10"
    _drive(seq, frames=2)
    (seq / "poses.txt").unlink()  # scans without poses (as semantickitti-extra's)
    (seq / "velodyne" / "000002.bin").write_bytes(b"")  # a scan without labels is not one
    out = tmp_path / "frames"
    r = subprocess.run([sys.executable, str(TOOL), "frames", str(out), str(seq)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["s10_000000", "s10_000001"]
    p, lab = _read(out / "s10_000001", 0)
    p0, lab0 = _read(seq, 1)
    assert np.array_equal(p, p0) and np.array_equal(lab, lab0)
    assert (out / "s10_000001" / "poses.txt").read_text() == "1 0 0 0 0 1 0 0 0 0 1 0\n"
    assert (out / "s10_000001" / "calib.txt").read_text().startswith("Tr: 1 0 0 0 0 1 0 0 0 0 1 0")
    again = subprocess.run([sys.executable, str(TOOL), "frames", str(out), str(seq)], capture_output=True, text=True)
    assert again.returncode != 0 and "exists" in again.stderr
    np.zeros(5, np.uint32).tofile(seq / "labels" / "000000.label")
    bad = subprocess.run([sys.executable, str(TOOL), "frames", str(tmp_path / "f2"), str(seq)], capture_output=True, text=True)
    assert bad.returncode != 0 and "1200 points but 5 labels" in bad.stderr
    assert not (tmp_path / "f2" / "s10_000000").exists()


def test_score_single_maps_each_drive_alone_and_with_its_terrain_model(tmp_path):
    from conftest import BIN, SHARED, SRC
    seq = SHARED / "data/semantickitti-extra/sequences/10"
    if not (seq / "velodyne/000000.bin").exists():
        pytest.skip(f"{seq} is absent (the shared data is not beside this checkout)")
    if not (BIN / "rawlog-octomap").exists():
        pytest.skip(f"{BIN}/rawlog-octomap is not built")
    work = tmp_path / "w"
    (work / "velodyne").mkdir(parents=True)
    (work / "labels").mkdir()
    (work / "velodyne/000000.bin").write_bytes((seq / "velodyne/000000.bin").read_bytes())
    (work / "labels/000000.label").write_bytes((seq / "labels/000000.label").read_bytes())
    (work / "poses.txt").write_text("1 0 0 0 0 1 0 0 0 0 1 0\n")
    (work / "calib.txt").write_text("Tr: 1 0 0 0 0 1 0 0 0 0 1 0\n")
    out = tmp_path / "out"
    out.mkdir()
    (out / "s10").symlink_to(work)
    r = subprocess.run([sys.executable, str(TOOL), "score", str(out), str(BIN), str(SRC / "config/kitti_hdl64.yaml"), "--single"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    line = r.stdout.splitlines()[0]
    assert line.startswith("s10 ") and line.count("|") == 1, line
    single, model = ([float(x) for x in part.replace("%", "").split()[1::2][:3]] for part in line[4:].split("|"))
    assert "driveTerrain: false" in (out / "config_single_fixed_height.yaml").read_text()
    assert (out / "maps/single_s10_costmap.yaml").exists() and (out / "maps/s10_costmap.yaml").exists()
    # One rural frame (sequence 10): the model finds ground the scan alone left out (89.1 -> 92.0).
    assert model[1] > single[1] + 1, line
