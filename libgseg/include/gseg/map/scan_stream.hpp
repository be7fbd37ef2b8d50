#pragma once
/// \file scan_stream.hpp
/// The scans of a rawlog, one at a time and in order, each with its robot pose: what the map
/// builder's producer reads (MapBuilder::run()). Nothing but the current scan (and the one being
/// completed) is held.
///
/// A scan is one raw LiDAR observation, or the `<label>_ground` / `<label>_obstacles` pair that
/// rawlog-gseg writes. Consecutive observations with the same base label and time stamp belong to
/// one scan; when it has a pair, the pair is used and the raw observation is not segmented again.
///
/// Poses, in this order of preference:
///   a TUM file (`t x y z qx qy qz qw`): the vehicle pose, matched to scans by time stamp;
///   a KITTI file (3x4 per scan, camera-0) + calib.txt: the velodyne pose of scan k
///     (Tr^-1 * P_k * Tr), scans taken in order;
///   the rawlog's own: CObservationRobotPose (absolute, as kitti2rawlog writes), CObservationOdometry
///     (absolute 2D odometry), CActionRobotMovement2D/3D (increments, integrated from the origin).

#include <gseg/map/poses.hpp>
#include <gseg/mrpt/rawlog_io.hpp>

#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

#include <deque>
#include <optional>
#include <string>
#include <vector>

namespace gseg::map {

/// Where the poses come from and how the world is shifted.
struct PoseConfig {
    std::string input;              ///< the rawlog (for messages)
    std::string poses, calib;       ///< --poses, --calib ("" = from the rawlog / beside the poses)
    double poseTolerance = 0.02;    ///< [s] TUM matching
    std::string origin;             ///< --origin: "" none, "first", or "X,Y,Z"
};

/// One scan, ready for the per-scan work.
struct ScanJob {
    std::size_t index = 0;   ///< scan number, 0-based
    std::size_t entry = 0;   ///< rawlog entry of its first observation
    std::string label;       ///< sensor label without the part suffix
    double t = 0;            ///< [s] time stamp
    ::mrpt::obs::CObservation::Ptr raw, ground, obstacles;  ///< raw scan, or the pre-segmented parts
    ::mrpt::poses::CPose3D robotPose;                      ///< vehicle pose in the (shifted) world
    double fraction = 0;     ///< of the rawlog read when this scan was complete (progress)

    bool presegmented() const { return ground || obstacles; }
    std::string describe() const;  ///< "scan 3 ('VELODYNE' at rawlog entry 7, t = ... s)"

};

/// The scans of a rawlog with their poses (see the file comment).
class ScanStream {
public:
    /// Opens the rawlog and reads the pose files (errors naming file and line come here, before
    /// any scan is read).
    explicit ScanStream(const PoseConfig& config);

    /// The next scan; false at the end of the rawlog. Throws std::runtime_error naming the scan
    /// when it has no pose, and the entry when the rawlog is corrupt.
    bool next(ScanJob& job);
    /// Reads ahead until `n` scans are waiting (fewer at the end of the rawlog) and returns them;
    /// next() hands them out first (e.g. the first scans, for an estimate before any work).
    const std::deque<ScanJob>& prefetch(std::size_t n);

    std::size_t rawScansSeenWithTheirPair() const { return rawWithPair_; }  ///< raw scans not segmented again
    /// The world shift subtracted from every position (--origin), if any.
    const std::optional<Eigen::Vector3d>& origin() const { return shift_; }
    std::string poseSource() const;
    double readSeconds() const { return readSeconds_; }  ///< time spent reading and decoding

private:
    PoseConfig config_;
    gseg::mrpt::RawlogReader reader_;
    std::vector<StampedPose> tum_;
    std::vector<Eigen::Isometry3d> kitti_;
    std::optional<::mrpt::poses::CPose3D> rawlogPose_;  ///< current pose from the rawlog
    std::optional<Eigen::Vector3d> shift_;

    std::optional<ScanJob> open_;      ///< the scan being completed
    std::optional<::mrpt::poses::CPose3D> openPose_;  ///< rawlog pose when it was opened
    void fill(std::size_t n);  ///< reads until `n` scans are ready or the rawlog ends
    std::deque<ScanJob> ready_;
    std::size_t emitted_ = 0, rawWithPair_ = 0;
    bool eof_ = false;
    double readSeconds_ = 0;

    void visit(std::size_t entry, const std::shared_ptr<::mrpt::serialization::CSerializable>& obj);
    void observation(std::size_t entry, const ::mrpt::obs::CObservation::Ptr& obs);
    void close();
    ::mrpt::poses::CPose3D poseOf(const ScanJob& job, const std::optional<::mrpt::poses::CPose3D>& rawlogPose);
};

}  // namespace gseg::map
