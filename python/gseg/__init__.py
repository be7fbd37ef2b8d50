"""gseg: GSeg3D high-precision LiDAR ground segmentation, from Python.

The C++ library on numpy arrays: the same labels as the command-line tools (`gseg segment`), the
same scores as `gseg eval`.

    import gseg
    points = gseg.read_kitti_bin("000000.bin")           # float32 (N, 4): x, y, z, intensity
    result = gseg.segment(points, config="config/kitti_hdl64.yaml")
    result.labels                                          # uint8 (N,): 1 ground, 0 non-ground

Classes: Params (the configuration; immutable, p.with_(key=value) makes a changed copy),
GroundSegmenter (one per thread; releases the GIL), Result, MapBuilder (traversability maps from
posed scans, as rawlog-octomap), RawlogScans (the posed scans of a rawlog, for MapBuilder).
Functions: segment, evaluate, read_kitti_bin, read_kitti_labels, read_ply, read_scan, write_ply.
Points are float32 (read in place) or float64 (copied) arrays; other dtypes raise TypeError.
Units are metres and degrees; points are in the sensor frame (x forward, y left, z up).
"""

from ._gseg import (GroundSegmenter, MapBuilder, Params, RawlogScans, Result, __version__, evaluate, read_kitti_bin, read_kitti_labels,
                    read_ply, read_scan, write_ply, _view_of)

__all__ = ["GroundSegmenter", "MapBuilder", "Params", "RawlogScans", "Result", "evaluate", "read_kitti_bin", "read_kitti_labels", "read_ply",
           "read_scan", "segment", "write_ply", "__version__"]


def segment(points, config=None, **params):
    """Segments one scan in one call: GroundSegmenter(Params(config, **params)).segment(points).

    points: numpy array (N, 3) or (N, 4) (x, y, z[, intensity]) [m], sensor frame, float32 or
            float64 (float32 with x, y, z consecutive is read without a copy; other dtypes,
            e.g. int32, raise TypeError: convert with points.astype(numpy.float32)).
    config: None (the defaults: KITTI HDL-64E parameters, the sensor height estimated per scan,
            distToGround "auto"), a YAML/INI file path as the tools take with -c, a dict, or a
            Params.
    params: keys of the configuration overriding it, e.g. distToGround="auto" or heightGate=0.1.
    Returns a Result (labels, ground_indices, nonground_indices, reflections, height, phase1,
    phase2, total_ms). Raises ValueError on bad parameters or points, TypeError on a wrong dtype.
    For many scans, keep one GroundSegmenter: it reuses its memory.
    """
    p = config if isinstance(config, Params) and not params else Params(config, **params)
    return GroundSegmenter(p).segment(points)
