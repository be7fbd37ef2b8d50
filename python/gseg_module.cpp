// gseg's Python module (_gseg): the core API on numpy arrays. The package gseg/__init__.py
// re-exports it. Points are viewed in place where their layout allows (float32, x y z
// consecutive, any fixed row stride), else converted once to float32 N x 3.
#include <gseg/drive_terrain.hpp>
#include <gseg/io/kitti.hpp>
#include <gseg/io/output_checks.hpp>
#include <gseg/io/ply.hpp>
#include <gseg/map/map_builder.hpp>
#include <gseg/map/scan_stream.hpp>
#include <gseg/eval/metrics.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/observation_points.hpp>
#include <gseg/mrpt/scan_source.hpp>
#include <gseg/mrpt/segment_scan.hpp>
#include <gseg/text.hpp>
#include <gseg/version.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/poses/CPose3D.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <memory>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace py = pybind11;

namespace {

/// Runs `f`; a library error (std::exception, not a Python one) becomes ValueError with its one-line
/// reason (MRPT's banner and backtrace left out).
template <class F>
auto asValueError(F&& f) -> decltype(f()) {
    try {
        return f();
    } catch (const py::builtin_exception&) {
        throw;
    } catch (const py::error_already_set&) {
        throw;
    } catch (const std::exception& e) {
        throw py::value_error(gseg::mrpt::errorReason(e));
    }
}

// --- numpy helpers ----------------------------------------------------------------------------

/// A vector handed to numpy without a copy (the array owns it through a capsule).
template <class T>
py::array_t<T> toNumpy(std::vector<T>&& v) {
    auto* owned = new std::vector<T>(std::move(v));
    py::capsule free(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
    return py::array_t<T>({py::ssize_t(owned->size())}, {py::ssize_t(sizeof(T))}, owned->data(), free);
}

/// Float rows of a N x C array (C = 4 for readers: x, y, z, intensity).
py::array_t<float> rowsToNumpy(std::vector<float>&& v, std::size_t columns) {
    const py::ssize_t n = py::ssize_t(v.size() / columns);
    auto* owned = new std::vector<float>(std::move(v));
    py::capsule free(owned, [](void* p) { delete static_cast<std::vector<float>*>(p); });
    return py::array_t<float>({n, py::ssize_t(columns)}, {py::ssize_t(columns * sizeof(float)), py::ssize_t(sizeof(float))},
                              owned->data(), free);
}

/// Points of a numpy array as a PointCloudView: in place for float32 with x, y, z consecutive,
/// else through a float32 copy held in `keep`. Throws ValueError/TypeError with the reason.
struct Points {
    gseg::PointCloudView view;
    py::object keep;  ///< the array the view points into
    bool copied = false;
};

Points viewPoints(const py::handle& obj) {
    if (!py::isinstance<py::array>(obj)) throw py::type_error("points must be a numpy array of shape (N, 3) or (N, 4), got " +
                                                              std::string(py::str(py::type::of(obj))));
    py::array a = py::reinterpret_borrow<py::array>(obj);
    if (a.ndim() != 2 || (a.shape(1) != 3 && a.shape(1) != 4))
        throw py::value_error("points must have shape (N, 3) or (N, 4) (x, y, z[, intensity]), got " +
                              std::string(py::str(py::tuple(py::cast(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()))))));
    if (a.shape(0) == 0) throw py::value_error("points is empty (0 rows)");
    // float32 (read in place) or float64 (one float32 copy); anything else is refused, naming the
    // fix: an int or float16 array is more likely a mistake than points.
    const bool f32 = a.dtype().is(py::dtype::of<float>());
    if (a.dtype().kind() != 'f' || (a.dtype().itemsize() != 4 && a.dtype().itemsize() != 8))
        throw py::type_error("points must be float32 or float64, got dtype " + std::string(py::str(a.dtype())) +
                             " (convert with points.astype(numpy.float32))");
    Points p;
    if (f32 && a.strides(1) == py::ssize_t(sizeof(float)) && a.strides(0) >= py::ssize_t(3 * sizeof(float)) &&
        a.strides(0) % py::ssize_t(sizeof(float)) == 0) {
        p.view = gseg::PointCloudView(static_cast<const float*>(a.data()), std::size_t(a.shape(0)), std::size_t(a.strides(0)));
        p.keep = a;
        return p;
    }
    // One converted copy: x, y, z as float32, C order.
    py::array_t<float, py::array::c_style | py::array::forcecast> c(a[py::make_tuple(py::slice(py::none(), py::none(), py::none()),
                                                                                      py::slice(0, 3, 1))]);
    p.view = gseg::PointCloudView(c.data(), std::size_t(c.shape(0)), std::size_t(c.strides(0)));
    p.keep = c;
    p.copied = true;
    return p;
}

template <class T>
std::vector<T> vectorOf(const py::handle& obj, const char* name, std::size_t expected) {
    py::array a;
    try {
        a = py::array::ensure(obj);
    } catch (...) {
    }
    if (!a) throw py::type_error(std::string(name) + " must be a 1-D array");
    if (a.ndim() != 1) throw py::value_error(std::string(name) + " must be 1-D, got " + std::to_string(a.ndim()) + " dimensions");
    if (std::size_t(a.shape(0)) != expected)
        throw py::value_error(std::string(name) + " has " + std::to_string(a.shape(0)) + " entries for " + std::to_string(expected) +
                              " points");
    const auto kind = a.dtype().kind();
    if (kind != 'i' && kind != 'u' && kind != 'b')
        throw py::type_error(std::string(name) + " must hold integers, got dtype " + std::string(py::str(a.dtype())));
    py::array_t<T, py::array::c_style | py::array::forcecast> c(a);
    return std::vector<T>(c.data(), c.data() + c.size());
}

// --- configuration ------------------------------------------------------------------------------

/// Python value -> the text a configuration file would hold for it.
std::string configText(const py::handle& v, const std::string& key) {
    if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
    if (py::isinstance<py::int_>(v)) return std::string(py::str(v));
    if (py::isinstance<py::float_>(v)) {
        std::ostringstream s;
        s.precision(17);
        s << v.cast<double>();
        return s.str();
    }
    if (py::isinstance<py::str>(v)) return v.cast<std::string>();
    throw py::value_error("parameter '" + key + "': cannot use a " + std::string(py::str(py::type::of(v).attr("__name__"))) +
                          " as its value");
}

/// Refuses a key that is not one of `known`, with the nearest one: "unknown parameter
/// 'distToGrund' (did you mean 'distToGround'?); gseg.Params.keys() lists them".
void checkKey(const std::string& key, const std::vector<std::string>& known, const std::string& what, const std::string& list) {
    if (std::find(known.begin(), known.end(), key) != known.end()) return;
    const py::list near = py::module_::import("difflib").attr("get_close_matches")(key, py::cast(known), 1, 0.6);
    throw py::value_error("unknown " + what + " '" + key + "'" +
                          (near.empty() ? std::string() : " (did you mean '" + std::string(py::str(near[0])) + "'?)") + "; " + list +
                          " lists them");
}

/// "parameters:2: ..." names a line of the text configFromDict() makes, not of any file: left out.
std::string withoutTextLine(std::string m) {
    if (m.rfind("parameters", 0) == 0) {
        std::size_t at = 10;
        if (at < m.size() && m[at] == ':') ++at;
        while (at < m.size() && std::isdigit(static_cast<unsigned char>(m[at]))) ++at;
        if (at < m.size() && m[at] == ':') ++at;
        while (at < m.size() && m[at] == ' ') ++at;
        m.erase(0, at);
    }
    return m;
}

/// Keyword arguments or a dict -> YAML text -> the one configuration loader (same keys, checks
/// and messages as the files). Nested dicts: `sensorHeight`, `traversability`.
gseg::mrpt::LoadedConfig configFromDict(const py::dict& d) {
    std::vector<std::string> top = gseg::Params::keys();
    top.insert(top.end(), {"distToGround", "sensorHeight", "traversability"});
    for (const auto& r : gseg::mrpt::retiredKeys()) top.push_back(r.key);  // loaded with a warning
    for (const auto& item : d) {
        const std::string key = py::str(item.first);
        checkKey(key, top, "parameter", "gseg.Params.keys()");
        if (key == "sensorHeight" && py::isinstance<py::dict>(item.second))
            for (const auto& sub : item.second.cast<py::dict>())
                checkKey(py::str(sub.first), gseg::SensorHeightOptions::keys(), "sensorHeight option", "Params().sensorHeight");
        if (key == "traversability" && py::isinstance<py::dict>(item.second))
            for (const auto& sub : item.second.cast<py::dict>())
                checkKey(py::str(sub.first), gseg::map::TraversabilityOptions::keys(), "traversability option",
                         "Params().traversability");
    }
    std::string text;
    std::string nested;
    for (const auto& item : d) {
        const std::string key = py::str(item.first);
        if (py::isinstance<py::dict>(item.second)) {
            nested += key + ":\n";
            for (const auto& sub : item.second.cast<py::dict>()) {
                const std::string k = py::str(sub.first);
                nested += "  " + k + ": \"" + configText(sub.second, key + "." + k) + "\"\n";
            }
            continue;
        }
        const std::string value = configText(item.second, key);
        if (value.find_first_of("\"\n") != std::string::npos) throw py::value_error("parameter '" + key + "': invalid value");
        text += key + ": \"" + value + "\"\n";
    }
    try {
        return gseg::mrpt::loadConfigFromText(text + nested, gseg::mrpt::ConfigFormat::Yaml, "parameters");
    } catch (const std::exception& e) {
        throw py::value_error(withoutTextLine(gseg::mrpt::errorReason(e)));
    }
}

/// The configuration's warnings (a retired key) as Python warnings, each once.
void warnAbout(const gseg::mrpt::LoadedConfig& c) {
    for (const std::string& w : c.warnings)
        py::module_::import("warnings").attr("warn")(withoutTextLine(w), py::handle(PyExc_UserWarning), 1);
}

/// The configuration as a dict of Python values (numbers as float/int/bool where they read so).
py::object valueOf(const std::string& text) {
    if (text == "true") return py::bool_(true);
    if (text == "false") return py::bool_(false);
    if (const auto i = gseg::parseNumber<long long>(text)) return py::int_(*i);
    if (const auto f = gseg::parseNumber<double>(text)) return py::float_(*f);
    return py::str(text);
}

py::dict configDict(const gseg::mrpt::LoadedConfig& c) {
    py::dict d;
    for (const auto& k : gseg::Params::keys()) d[py::str(k)] = valueOf(c.params.get(k));
    if (c.distToGroundAuto) d["distToGround"] = py::str("auto");
    py::dict sh, tr;
    for (const auto& k : gseg::SensorHeightOptions::keys()) sh[py::str(k)] = valueOf(c.sensorHeight.get(k));
    for (const auto& k : gseg::map::TraversabilityOptions::keys()) tr[py::str(k)] = valueOf(c.traversability.get(k));
    d["sensorHeight"] = sh;
    d["traversability"] = tr;
    return d;
}

/// Params: a loaded configuration (gseg::Params plus distToGround auto, sensorHeight,
/// traversability), immutable once made, as the library's.
struct PyParams {
    gseg::mrpt::LoadedConfig config = gseg::mrpt::defaultConfig();
};

PyParams paramsFrom(const py::object& source, const py::kwargs& kwargs) {
    py::dict d;
    if (!source.is_none()) {
        if (py::isinstance<py::dict>(source)) {
            for (const auto& item : source.cast<py::dict>()) d[item.first] = item.second;
        } else if (py::isinstance<PyParams>(source)) {
            d = configDict(source.cast<const PyParams&>().config);
        } else if (py::isinstance<py::str>(source) || py::hasattr(source, "__fspath__")) {
            const std::string path = py::str(py::module_::import("os").attr("fspath")(source));
            PyParams p;
            try {
                p.config = gseg::mrpt::loadConfig(path);
            } catch (const std::exception& e) {
                throw py::value_error(gseg::mrpt::errorReason(e));
            }
            warnAbout(p.config);
            if (kwargs.empty()) return p;
            d = configDict(p.config);
        } else {
            throw py::type_error("Params() takes a dict, a configuration file path or another Params");
        }
    }
    for (const auto& item : kwargs) {
        const std::string key = py::str(item.first);
        if ((key == "sensorHeight" || key == "traversability") && d.contains(item.first) && py::isinstance<py::dict>(item.second)) {
            py::dict merged = d[item.first].cast<py::dict>();
            for (const auto& sub : item.second.cast<py::dict>()) merged[sub.first] = sub.second;
            d[item.first] = merged;
        } else {
            d[item.first] = item.second;
        }
    }
    PyParams p{configFromDict(d)};
    warnAbout(p.config);
    return p;
}

// --- results ------------------------------------------------------------------------------------

py::dict phaseDict(const gseg::PhaseReport& p) {
    py::dict d;
    d["input_points"] = p.inputPoints;
    d["ground_points"] = p.groundPoints;
    d["occupied_cells"] = p.occupiedCells;
    d["candidate_cells"] = p.candidateCells;
    d["ground_cells"] = p.groundCells;
    d["unlabelled_cell_points"] = p.unlabelledCellPoints;
    d["unreached_cell_points"] = p.unreachedCellPoints;
    d["recovered_points"] = p.recoveredPoints;
    py::dict ms;
    ms["grid"] = p.ms.grid;
    ms["classification"] = p.ms.classification;
    ms["plane_fit"] = p.ms.planeFit;
    ms["expansion"] = p.ms.expansion;
    ms["refinement"] = p.ms.refinement;
    ms["total"] = p.ms.total();
    d["ms"] = ms;
    return d;
}

const char* sourceName(const gseg::mrpt::ScanSegmentation& s) {
    if (!s.autoHeight) return "fixed";
    switch (s.height.source) {
        case gseg::HeightDecision::Source::Estimated: return "estimated";
        case gseg::HeightDecision::Source::PreviousScan: return "previous scan";
        case gseg::HeightDecision::Source::Fallback: return "fallback";
    }
    return "fallback";
}

py::dict heightDict(const gseg::mrpt::ScanSegmentation& s) {
    py::dict d;
    d["dist_to_ground"] = s.distToGround;
    d["auto"] = s.autoHeight;
    d["estimated"] = s.distToGroundEstimated;
    d["source"] = sourceName(s);
    d["tilt_degrees"] = s.autoHeight ? s.height.tiltDegrees : 0.0;
    d["description"] = s.autoHeight ? s.height.describe() : std::string();
    d["warning"] = s.heightWarning;
    return d;
}

/// The result of one segment() call, handed to Python.
struct PyResult {
    py::array_t<std::uint8_t> labels;
    py::array_t<std::uint32_t> groundIndices, nonGroundIndices, reflectionIndices;
    py::array_t<bool> reflections;
    std::size_t numGround = 0, numNonGround = 0, numNonFinite = 0;
    py::dict height, phase1, phase2;
    double totalMs = 0;
};

PyResult toPython(gseg::mrpt::ScanSegmentation&& s, std::size_t points) {
    PyResult r;
    std::vector<std::uint32_t> ground, nonGround;
    ground.reserve(s.result.numGround);
    nonGround.reserve(points - s.result.numGround);
    for (std::size_t i = 0; i < s.result.labels.size(); ++i) (s.result.labels[i] ? ground : nonGround).push_back(std::uint32_t(i));
    py::array_t<bool> flags{py::ssize_t(points)};
    bool* f = flags.mutable_data();
    std::fill(f, f + points, false);
    for (std::uint32_t i : s.result.belowGround) f[i] = true;
    r.numGround = s.result.numGround;
    r.numNonGround = s.result.numNonGround;
    r.numNonFinite = s.result.numNonFinite;
    r.totalMs = s.result.totalMs;
    r.height = heightDict(s);
    r.phase1 = phaseDict(s.result.phase1);
    r.phase2 = phaseDict(s.result.phase2);
    r.labels = toNumpy(std::move(s.result.labels));
    r.groundIndices = toNumpy(std::move(ground));
    r.nonGroundIndices = toNumpy(std::move(nonGround));
    r.reflectionIndices = toNumpy(std::move(s.result.belowGround));
    r.reflections = flags;
    return r;
}

/// GroundSegmenter: segment() releases the GIL and then takes the object's mutex (it keeps scratch
/// memory): threads sharing one segmenter take turns and get the labels of serial calls; one
/// segmenter per thread segments in parallel. The mutex is taken only with the GIL released (never
/// the other way round), so a thread waiting for it never blocks the thread that holds it.
/// A 4 x 4 rigid transform given from Python (ValueError naming `name` otherwise).
::mrpt::poses::CPose3D poseOf(const py::handle& obj, const char* name);

class PySegmenter {
public:
    explicit PySegmenter(const PyParams& p) : segmenter_(p.config), params_(p) {}

    PyResult segment(const py::handle& points, bool checkHeight, const py::handle& pose) {
        Points p = viewPoints(points);
        const std::optional<::mrpt::poses::CPose3D> sensorPose =
            pose.is_none() ? std::nullopt : std::optional<::mrpt::poses::CPose3D>(poseOf(pose, "pose"));
        bool anyFinite = false;
        for (std::size_t i = 0; i < p.view.size() && !anyFinite; ++i) {
            const float* q = p.view.point(i);
            anyFinite = std::isfinite(q[0]) && std::isfinite(q[1]) && std::isfinite(q[2]);
        }
        if (!anyFinite) throw py::value_error("points has no finite point (every row holds a NaN or an infinity)");
        gseg::mrpt::ScanSegmentation s;
        {
            py::gil_scoped_release release;
            const std::lock_guard<std::mutex> lock(mutex_);
            s = segmenter_.segment(p.view, false, checkHeight ? gseg::mrpt::HeightCheck::Now : gseg::mrpt::HeightCheck::Never);
            const gseg::map::TraversabilityOptions& t = params_.config.traversability;
            if (sensorPose && t.driveTerrain) {  // the drive's context, causal: the scans given before with their poses
                const std::vector<float> world = gseg::mrpt::transformedPoints(p.view, *sensorPose);
                if (!drive_) drive_ = std::make_unique<gseg::DriveTerrain>(t.terrainOptions(), t.maxRange);
                drive_->label(gseg::PointCloudView(world.data(), p.view.size()), s.result,
                              Eigen::Vector3d(sensorPose->x(), sensorPose->y(), sensorPose->z()));
            }
        }
        return toPython(std::move(s), p.view.size());
    }
    const PyParams& params() const { return params_; }

private:
    gseg::mrpt::ScanSegmenter segmenter_;
    PyParams params_;
    std::unique_ptr<gseg::DriveTerrain> drive_;  ///< the drive's terrain model of the scans given with a pose
    std::mutex mutex_;
};

py::dict countsDict(const gseg::Counts& c) {
    py::dict d;
    d["tp"] = c.tp;
    d["fp"] = c.fp;
    d["fn"] = c.fn;
    d["tn"] = c.tn;
    d["precision"] = c.precision();
    d["recall"] = c.recall();
    d["f1"] = c.f1();
    return d;
}

void checkNewOutput(const std::string& path, bool overwrite) {
    try {
        gseg::io::checkOutputs({}, {{"path", path}}, gseg::io::OutputRules{overwrite, false});
    } catch (const std::invalid_argument& e) {
        // e.g. "path x.ply exists (give overwrite=True to replace it)"
        std::string m = e.what();
        const std::string flag = "-w";
        const auto at = m.find(flag);
        if (at != std::string::npos && !overwrite) m = m.substr(0, at) + "overwrite=True" + m.substr(at + flag.size());
        throw py::value_error(m);
    }
}

// --- maps -----------------------------------------------------------------------------------------

/// A 4 x 4 rigid transform (numpy) as a CPose3D; ValueError unless finite with a rotation block.
::mrpt::poses::CPose3D poseOf(const py::handle& obj, const char* name) {
    py::array_t<double, py::array::c_style | py::array::forcecast> a;
    try {
        a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
    } catch (...) {
    }
    if (!a || a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4) throw py::value_error(std::string(name) + " must be a 4 x 4 matrix");
    ::mrpt::math::CMatrixDouble44 m;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) {
            m(r, c) = a.at(r, c);
            if (!std::isfinite(m(r, c))) throw py::value_error(std::string(name) + " holds a NaN or an infinity");
        }
    Eigen::Matrix3d rot;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) rot(r, c) = m(r, c);
    if (m(3, 0) != 0 || m(3, 1) != 0 || m(3, 2) != 0 || m(3, 3) != 1 || !(rot.transpose() * rot).isIdentity(1e-3) ||
        rot.determinant() < 0)
        throw py::value_error(std::string(name) + " is not a rigid transform (rotation and translation, last row 0 0 0 1)");
    return ::mrpt::poses::CPose3D(m);
}

py::array_t<double> matrixOf(const ::mrpt::poses::CPose3D& p) {
    py::array_t<double> out({4, 4});
    const auto m = p.getHomogeneousMatrixVal<::mrpt::math::CMatrixDouble44>();
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) out.mutable_at(r, c) = m(r, c);
    return out;
}

/// The scans of a rawlog with their poses, as MapBuilder.insert() takes them (an iterator).
class PyRawlogScans {
public:
    PyRawlogScans(const std::filesystem::path& rawlog, const std::filesystem::path& poses, const std::filesystem::path& calib) {
        gseg::map::PoseConfig c;
        c.input = rawlog.string();
        c.poses = poses.string();
        c.calib = calib.string();
        try {
            stream_ = std::make_unique<gseg::map::ScanStream>(c);
        } catch (const std::exception& e) {
            throw py::value_error(gseg::mrpt::errorReason(e));
        }
    }
    py::tuple next() {
        gseg::map::ScanJob job;
        std::vector<float> xyzi;
        ::mrpt::poses::CPose3D sensorPose;
        {
            py::gil_scoped_release release;
            const std::lock_guard<std::mutex> lock(mutex_);  // one reader: threads sharing the iterator take turns
            try {
                for (;;) {
                    if (!stream_->next(job)) break;
                    if (!job.raw) continue;  // a rawlog-gseg pair without its raw scan
                    job.raw->getSensorPose(sensorPose);
                    xyzi = gseg::mrpt::sensorFramePoints(*job.raw);
                    break;
                }
            } catch (const std::exception& e) {
                py::gil_scoped_acquire acquire;
                throw py::value_error(gseg::mrpt::errorReason(e));
            }
        }
        if (!job.raw) throw py::stop_iteration();
        return py::make_tuple(rowsToNumpy(std::move(xyzi), 4), matrixOf(job.robotPose), matrixOf(sensorPose), job.describe());
    }

private:
    std::unique_ptr<gseg::map::ScanStream> stream_;
    std::mutex mutex_;
};

py::dict statsDict(const gseg::map::MapStats& s) {
    py::dict d;
    d["scans"] = s.scans;
    d["ground_points"] = s.groundPoints;
    d["obstacle_points"] = s.obstaclePoints;
    d["points_skipped"] = s.pointsSkipped;
    d["rays"] = s.rays;
    d["ground_voxels"] = s.groundVoxels;
    d["obstacle_voxels"] = s.obstacleVoxels;
    d["free_voxels"] = s.freeVoxels;
    d["cells_traversable"] = s.cellsTraversable;
    d["cells_obstacle"] = s.cellsObstacle;
    d["costmap_free"] = s.costmapFree;  // the costmap PGM's cells: what a planner loads
    d["costmap_occupied"] = s.costmapOccupied;
    d["costmap_unknown"] = s.costmapUnknown;
    d["path_length"] = s.pathLength;
    return d;
}

/// The map builder of rawlog-octomap, fed scan by scan. Every method that touches the builder
/// releases the GIL and then takes the object's mutex (as PySegmenter): threads sharing one builder
/// insert one scan at a time, in the order they get the mutex.
class PyMapBuilder {
public:
    explicit PyMapBuilder(const PyParams& p) : builder_(p.config, p.config.traversability) {}

    bool insert(const py::handle& points, const py::handle& pose, const py::handle& sensorPose) {
        Points p = viewPoints(points);
        const ::mrpt::poses::CPose3D robot = poseOf(pose, "pose");
        const ::mrpt::poses::CPose3D mount = sensorPose.is_none() ? ::mrpt::poses::CPose3D() : poseOf(sensorPose, "sensor_pose");
        // x, y, z, intensity as the observation holds them (intensity 0 for N x 3 input).
        std::vector<float> xyzi(4 * p.view.size(), 0.f);
        py::array a = py::reinterpret_borrow<py::array>(points);
        const bool withIntensity = a.shape(1) == 4;
        py::array_t<float, py::array::forcecast> fa(a);
        const auto f = fa.unchecked<2>();
        for (py::ssize_t i = 0; i < f.shape(0); ++i)
            for (py::ssize_t c = 0; c < (withIntensity ? 4 : 3); ++c) xyzi[std::size_t(4 * i + c)] = f(i, c);
        bool anyFinite = false;
        for (std::size_t i = 0; i < p.view.size() && !anyFinite; ++i) {
            const float* q = p.view.point(i);
            anyFinite = std::isfinite(q[0]) && std::isfinite(q[1]) && std::isfinite(q[2]);
        }
        const auto obs = gseg::mrpt::pointCloudObservation(xyzi.data(), p.view.size(), mount, "LIDAR",
                                                           ::mrpt::Clock::fromDouble(double(scans_)));
        const std::size_t index = scans_++;  // under the GIL
        py::gil_scoped_release release;
        const std::lock_guard<std::mutex> lock(mutex_);
        if (!anyFinite) {  // skipped and said so (the map is unchanged), as a scan the segmenter refuses
            gseg::map::ScanResult r;
            r.describe = "scan " + std::to_string(index);
            r.skipped = "no finite point (every row holds a NaN or an infinity)";
            builder_.integrate(r);
            return false;
        }
        try {
            return builder_.insert(*obs, robot);
        } catch (const std::exception& e) {
            py::gil_scoped_acquire acquire;
            throw py::value_error(gseg::mrpt::errorReason(e));
        }
    }

    std::vector<std::string> write(const std::filesystem::path& prefixPath, bool overwrite) {
        const std::string prefix = prefixPath.string();
        if (prefix.empty()) throw py::value_error("prefix is empty (it starts the name of every file written, e.g. 'out/map')");
        if (empty()) throw py::value_error("no scan was inserted: nothing to write");
        std::vector<gseg::io::NamedPath> outputs;
        for (const auto& path : gseg::map::TraversabilityMap::pathsToCheck(prefix)) outputs.push_back({"prefix", path});
        try {
            gseg::io::checkOutputs({}, outputs, gseg::io::OutputRules{overwrite, false});
        } catch (const std::invalid_argument& e) {
            std::string m = e.what();
            const auto at = m.find("-w");
            if (at != std::string::npos) m = m.substr(0, at) + "overwrite=True" + m.substr(at + 2);
            throw py::value_error(m);
        }
        py::gil_scoped_release release;
        const std::lock_guard<std::mutex> lock(mutex_);
        try {
            return builder_.map().write(prefix);
        } catch (const std::exception& e) {
            py::gil_scoped_acquire acquire;
            throw py::value_error(gseg::mrpt::errorReason(e));
        }
    }

    py::dict stats() {
        gseg::map::MapStats s;
        {
            py::gil_scoped_release release;
            const std::lock_guard<std::mutex> lock(mutex_);
            s = builder_.map().stats();
        }
        return statsDict(s);
    }
    std::vector<std::string> skipped() {
        py::gil_scoped_release release;
        const std::lock_guard<std::mutex> lock(mutex_);
        return builder_.tally().skipped;
    }

private:
    bool empty() {
        py::gil_scoped_release release;
        const std::lock_guard<std::mutex> lock(mutex_);
        return builder_.map().empty();
    }

    gseg::map::MapBuilder builder_;
    std::size_t scans_ = 0;
    std::mutex mutex_;
};

}  // namespace

PYBIND11_MODULE(_gseg, m) {
    m.doc() = "gseg: GSeg3D LiDAR ground segmentation (C++ core, numpy arrays in and out).";
    m.attr("__version__") = GSEG_VERSION;

    py::class_<PyParams>(m, "Params", R"doc(
The configuration of the segmenter: every key of gseg's params.hpp (the YAML/INI keys, e.g.
distToGround [m], cellSizeX [m], heightGate [m]), distToGround="auto" to estimate the sensor
height per scan, and the nested sensorHeight / traversability options.

Params()                        the defaults of the tools without a configuration file: the
                                KITTI HDL-64E parameters with distToGround "auto" (the sensor
                                height estimated per scan; 1.723 m where a scan gives no estimate)
Params(distToGround=1.8, ...)   keyword arguments
Params({"distToGround": "auto"}) a dict
Params("config/vlp16.yaml")     a YAML or INI file (as the tools read them), optionally with
                                keyword arguments that override its values
distToGround is "auto" wherever it is not given (as in the files); give a number to fix it.
Unknown keys raise ValueError naming the key and the nearest valid one ("did you mean"); invalid
values raise ValueError naming the key. Read a value as p.heightGate or p["heightGate"].
Params are immutable (a GroundSegmenter keeps the ones it was made with): p.heightGate = 0.2
raises AttributeError; make a changed copy with p.with_(heightGate=0.2), the same as
Params(p, heightGate=0.2).)doc")
        .def(py::init([](const py::object& source, const py::kwargs& kwargs) { return paramsFrom(source, kwargs); }),
             py::arg("source") = py::none())
        .def("with_", [](const py::object& self, const py::kwargs& kwargs) { return paramsFrom(self, kwargs); },
             "A copy with the keys given changed: p.with_(heightGate=0.2) (Params(p, heightGate=0.2)). Raises "
             "ValueError as Params().")
        .def("__setattr__", [](const PyParams&, const std::string& key, const py::object&) {
            throw py::attribute_error("Params is immutable: '" + key + "' cannot be set; make a changed copy with p.with_(" + key +
                                      "=...) (the same as gseg.Params(p, " + key + "=...))");
        })
        .def("__delattr__", [](const PyParams&, const std::string& key) {
            throw py::attribute_error("Params is immutable: '" + key + "' cannot be deleted; p.with_(...) makes a changed copy");
        })
        .def("to_dict", [](const PyParams& p) { return configDict(p.config); }, "Every key and its value (a dict).")
        .def("to_yaml", [](const PyParams& p) { return gseg::mrpt::toYaml(p.config); },
             "The configuration as a YAML file the tools read (-c).")
        .def_static("keys", []() { return gseg::Params::keys(); }, "The segmentation keys, in declaration order.")
        .def("__getitem__", [](const PyParams& p, const std::string& key) {
            py::dict d = configDict(p.config);
            if (!d.contains(key)) throw py::key_error("no parameter '" + key + "'");
            return py::object(d[py::str(key)]);
        })
        .def("__getattr__", [](const PyParams& p, const std::string& key) {
            py::dict d = configDict(p.config);
            if (!d.contains(key)) throw py::attribute_error("no parameter '" + key + "'");
            return py::object(d[py::str(key)]);
        })
        .def("__eq__", [](const PyParams& a, const PyParams& b) { return gseg::mrpt::toYaml(a.config) == gseg::mrpt::toYaml(b.config); })
        .def("__repr__", [](const PyParams& p) {
            return std::string("gseg.Params(distToGround=") +
                   (p.config.distToGroundAuto ? std::string("'auto'") : p.config.params.get("distToGround")) + ", ...)";
        });

    py::class_<PyResult>(m, "Result", "The labels of one scan and how they came about (from GroundSegmenter.segment()).")
        .def_readonly("labels", &PyResult::labels, "uint8 array, one per point in input order: 1 ground, 0 non-ground")
        .def_readonly("ground_indices", &PyResult::groundIndices, "uint32 indices of the ground points (ascending)")
        .def_readonly("nonground_indices", &PyResult::nonGroundIndices, "uint32 indices of the non-ground points (ascending)")
        .def_readonly("reflections", &PyResult::reflections,
                      "bool array, one per point: non-ground points far below the local ground (mirror reflections, "
                      "multipath; belowGroundMargin), which maps leave out")
        .def_readonly("reflection_indices", &PyResult::reflectionIndices, "uint32 indices of those points (ascending)")
        .def_readonly("num_ground", &PyResult::numGround)
        .def_readonly("num_nonground", &PyResult::numNonGround)
        .def_readonly("num_nonfinite", &PyResult::numNonFinite, "points with a NaN or infinite coordinate (labelled non-ground)")
        .def_readonly("height", &PyResult::height,
                      "the sensor height used: dist_to_ground [m], auto, estimated, source ('fixed', 'estimated', "
                      "'fallback'), tilt_degrees, description, warning")
        .def_readonly("phase1", &PyResult::phase1, "Phase I (tall cells) counters and step times [ms]")
        .def_readonly("phase2", &PyResult::phase2, "Phase II (thin cells) counters and step times [ms]")
        .def_readonly("total_ms", &PyResult::totalMs, "[ms] time of the segmentation")
        .def("__repr__", [](const PyResult& r) {
            return "gseg.Result(" + std::to_string(r.numGround) + " ground, " + std::to_string(r.numNonGround) + " non-ground)";
        });

    py::class_<PySegmenter>(m, "GroundSegmenter", R"doc(
GSeg3D ground segmentation with one configuration (Params). Deterministic: the same points give
the same labels on every call. segment() releases the GIL: one segmenter per thread segments in
parallel; threads sharing one segmenter are safe and get the same labels, but take turns (it keeps
scratch memory between calls, guarded by a lock).)doc")
        .def(py::init([](const py::object& params) {
                 return std::make_unique<PySegmenter>(params.is_none() ? PyParams{} : params.cast<PyParams>());
             }),
             py::arg("params") = py::none())
        .def("segment", &PySegmenter::segment, py::arg("points"), py::arg("check_height") = false, py::arg("pose") = py::none(), R"doc(
Labels every point.

points: numpy array (N, 3) or (N, 4) (x, y, z[, intensity]) in metres, sensor frame (x forward,
        y left, z up, sensor at the origin), float32 or float64. A float32 array whose x, y, z are
        consecutive (C order, any row stride) is read in place, without a copy.
check_height: with a fixed distToGround, compare it with this scan's own estimate and put a
        warning in result.height['warning'] where they disagree (costs about one segmentation).
pose: the sensor's pose in the world frame (a 4 x 4 rigid transform, world from sensor),
        for scans of a drive given in the drive's order: the segmenter then keeps the drive's
        terrain model of the scans given before (causal) and labels ground the non-ground points
        lying on it (traversability.driveTerrain and terrain* keys; the area around the sensor is
        kept). Without a pose each scan is labelled alone, the same labels as gseg.segment().
Returns a Result. Raises ValueError on an empty array, a wrong shape or no finite point, TypeError
on a dtype other than float32 or float64 (convert with points.astype(numpy.float32)). Points with NaN/inf coordinates are labelled non-ground.)doc")
        .def_property_readonly("params", &PySegmenter::params);

    py::class_<PyRawlogScans>(m, "RawlogScans", R"doc(
The scans of an MRPT rawlog with their poses, in order, as rawlog-octomap reads them: iterate to
get (points, pose, sensor_pose, description) per scan: points float32 (N, 4) x, y, z, intensity in
the sensor frame; pose the 4 x 4 vehicle pose in the world; sensor_pose the sensor's mounting on
the vehicle (4 x 4). Poses come from the rawlog (kitti2rawlog's CObservationRobotPose, odometry,
actions) or from poses= (a TUM or KITTI poses file; calib= the KITTI calib.txt).)doc")
        .def(py::init<const std::filesystem::path&, const std::filesystem::path&, const std::filesystem::path&>(), py::arg("rawlog"),
             py::arg("poses") = "", py::arg("calib") = "")
        .def("__iter__", [](PyRawlogScans& s) -> PyRawlogScans& { return s; })
        .def("__next__", &PyRawlogScans::next);

    py::class_<PyMapBuilder>(m, "MapBuilder", R"doc(
Builds gseg's traversability maps from scans with poses, as rawlog-octomap does: each scan is
segmented with the configuration (Params: segmentation keys, distToGround or "auto", and the
`traversability` options: resolution [m], maxRange [m], clearance [m], ...), moved into the world
frame and ray-cast into the maps, in the order given. write() puts the same files as
`rawlog-octomap -o PREFIX` (byte for byte for the same scans and poses). Threads may share one
builder: its methods take a lock (with the GIL released), so scans go in one at a time.)doc")
        .def(py::init([](const py::object& params) {
                 return std::make_unique<PyMapBuilder>(params.is_none() ? PyParams{} : params.cast<PyParams>());
             }),
             py::arg("params") = py::none())
        .def("insert", &PyMapBuilder::insert, py::arg("points"), py::arg("pose"), py::arg("sensor_pose") = py::none(), R"doc(
Adds one scan. points: (N, 3) or (N, 4) array (x, y, z[, intensity]) [m] in the sensor frame;
pose: 4 x 4 rigid transform of the vehicle in the world frame [m]; sensor_pose: 4 x 4 mounting of
the sensor on the vehicle (default: identity, the sensor is the vehicle frame). Returns False when
the scan could not be used (its reason in skipped()). Raises ValueError on bad points or poses.)doc")
        .def("write", &PyMapBuilder::write, py::arg("prefix"), py::arg("overwrite") = false, R"doc(
Writes the files of `rawlog-octomap -o PREFIX`, all or none: PREFIX_ground.bt, PREFIX_obstacles.bt,
PREFIX_traversability.ot/.png/.ply/.3Dscene, the planner's costmap PREFIX_costmap.pgm + .yaml (ROS
map_server), the 2.5D layers PREFIX_layers.tif (GeoTIFF) and a picture per layer; returns their paths. Existing files raise
ValueError unless overwrite=True.)doc")
        .def("stats", &PyMapBuilder::stats, "Counters of the map: scans, points, rays, voxels, cells, path length [m], and the costmap's free / occupied / unknown cells (costmap_free, costmap_occupied, costmap_unknown: the PGM a planner loads).")
        .def("skipped", &PyMapBuilder::skipped, "Why scans were not used, one line each.");

    m.def("_view_of", [](const py::handle& points) {
        Points p = viewPoints(points);
        return py::make_tuple(reinterpret_cast<std::uintptr_t>(p.view.point(0)), p.view.strideBytes(), p.copied);
    }, py::arg("points"), "(address, stride in bytes, copied) of the point view segment() uses (for tests).");

    m.def("evaluate", [](const py::handle& points, const py::handle& labels, const py::handle& prediction) {
        Points p = viewPoints(points);
        const auto truth = vectorOf<std::uint32_t>(labels, "labels", p.view.size());
        const auto pred = vectorOf<std::uint8_t>(prediction, "prediction", p.view.size());
        gseg::FrameScore s;
        try {
            s = gseg::scoreFrame(p.view, truth, pred);
        } catch (const std::invalid_argument& e) {
            throw py::value_error(e.what());
        }
        py::dict d = countsDict(s.withVegetation);
        d["without_vegetation"] = countsDict(s.withoutVegetation);
        py::list byRange;
        const gseg::ProtocolOptions protocol;
        for (std::size_t k = 0; k < s.byRange.size(); ++k) {
            py::dict r = countsDict(s.byRange[k]);
            r["range"] = protocol.rangeLimits[k];
            byRange.append(r);
        }
        d["by_range"] = byRange;
        return d;
    }, py::arg("points"), py::arg("labels"), py::arg("prediction"), R"doc(
Scores a prediction against SemanticKITTI labels under the Ground Segmentation Benchmark protocol,
as `gseg eval` does (the same TP / FP / FN).

points: (N, 3|4) array; labels: N raw SemanticKITTI labels (uint32, class = value & 0xFFFF);
prediction: N values, 1 ground, 0 non-ground (e.g. Result.labels).
Returns a dict: tp, fp, fn, tn, precision, recall, f1 [%] (ground = road, parking, sidewalk,
other-ground, lane marking, terrain, and vegetation below -1.2975 m; unlabelled and outlier points
predicted ground count as true positives), 'without_vegetation' (vegetation don't-care) and
'by_range' (the same within 10, 20, ... 100 m horizontally).)doc");

    m.def("read_kitti_bin", [](const std::filesystem::path& path) {
        return asValueError([&] { return rowsToNumpy(gseg::io::readKittiBin(path.string()), 4); });
    }, py::arg("path"), "Reads a KITTI velodyne .bin: float32 array (N, 4) of x, y, z, intensity.");
    m.def("read_kitti_labels", [](const std::filesystem::path& path, py::object expected) {
        const std::size_t n = expected.is_none() ? SIZE_MAX : expected.cast<std::size_t>();
        return asValueError([&] { return toNumpy(gseg::io::readKittiLabels(path.string(), n)); });
    }, py::arg("path"), py::arg("points") = py::none(),
          "Reads a SemanticKITTI .label file: uint32 array (raw labels; class = value & 0xFFFF). With points=N, "
          "a file that does not hold N labels raises ValueError.");
    m.def("read_ply", [](const std::filesystem::path& path) {
        return asValueError([&] { return rowsToNumpy(gseg::io::readPly(path.string()), 4); });
    }, py::arg("path"), "Reads the vertices of a PLY file: float32 array (N, 4) of x, y, z, intensity (0 where absent).");
    m.def("read_scan", [](const std::filesystem::path& path, int index) {
        gseg::mrpt::Scan s = asValueError([&] { return gseg::mrpt::loadScan(path.string(), index); });
        return py::make_tuple(rowsToNumpy(std::move(s.xyzi), 4), s.description);
    }, py::arg("path"), py::arg("index") = -1, R"doc(
Reads one scan as the tools do (`gseg segment SCAN`): a KITTI .bin, a PLY, or the index-th LiDAR
observation of an MRPT rawlog (-1: the first; in the levelled sensor frame). Returns (points,
description): points a float32 array (N, 4).)doc");
    m.def("write_ply", [](const std::filesystem::path& path, const py::handle& points, const py::handle& labels, bool overwrite) {
        Points p = viewPoints(points);
        const auto l = vectorOf<std::uint8_t>(labels, "labels", p.view.size());
        for (auto v : l)
            if (v > 1) throw py::value_error("labels must be 0 (non-ground) or 1 (ground)");
        checkNewOutput(path.string(), overwrite);
        gseg::io::PlyOptions options;
        // (N, 4): the intensity too, as `gseg segment --ply-out` keeps it (x, y, z, intensity as float32, C order).
        py::array a = py::reinterpret_borrow<py::array>(points);
        py::array_t<float, py::array::c_style | py::array::forcecast> xyzi;
        if (a.shape(1) == 4) {
            xyzi = py::array_t<float, py::array::c_style | py::array::forcecast>(a);
            p.view = gseg::PointCloudView(xyzi.data(), std::size_t(xyzi.shape(0)), 4 * sizeof(float));
            options.intensity = true;
        }
        asValueError([&] { gseg::io::writeLabelledPly(path.string(), p.view, l, gseg::io::PlyColours(), options); });
    }, py::arg("path"), py::arg("points"), py::arg("labels"), py::arg("overwrite") = false, R"doc(
Writes a segmented scan as a binary PLY as `gseg segment --ply-out` does: x, y, z, the class
(scalar_class: 1 ground, 2 non-ground), the intensity when points has 4 columns, colour (green
ground, red non-ground) and label (1 ground, 0 non-ground); completely or not at all. An
existing file raises ValueError unless overwrite=True.)doc");
}
