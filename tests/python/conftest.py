"""Paths for the gseg Python tests (set by ctest: GSEG_BINARY_DIR, GSEG_SOURCE_DIR, GSEG_SHARED_DIR)."""
import os
import pathlib

import pytest

BIN = pathlib.Path(os.environ.get("GSEG_BINARY_DIR", "build")) / "bin"
SRC = pathlib.Path(os.environ.get("GSEG_SOURCE_DIR", "."))
SHARED = pathlib.Path(os.environ.get("GSEG_SHARED_DIR", "../shared"))
VLP16 = pathlib.Path("/usr/share/mrpt/datasets/test_velodyne_VLP16.rawlog")


def labelled_scans():
    """Every labelled scan of ../shared/data: (bin, label) pairs, sorted."""
    out = []
    for bin_path in sorted((SHARED / "data").glob("*/sequences/*/velodyne/*.bin")):
        label = bin_path.parent.parent / "labels" / (bin_path.stem + ".label")
        if label.exists():
            out.append((bin_path, label))
    return out


@pytest.fixture
def kitti_scan():
    path = SHARED / "data/semantickitti/sequences/00/velodyne/000000.bin"
    if not path.exists():
        pytest.skip(f"{path} is absent (the shared data is not beside this checkout)")
    return path
