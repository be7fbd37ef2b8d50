#pragma once
/// \file scan_message.hpp
/// The wire format of the map route's per-scan work (#12): a scan (its observations and poses) sent
/// to a worker in another process, and the worker's result (its ScanUpdate, times and notes) or
/// its error sent back. Exact: the other side's observations and poses have the same values (so
/// the same points and the same voxels), and a result's bytes give back the same ScanResult.
/// Bytes through gseg::io::ByteWriter / ByteReader; a short or garbled message throws
/// std::runtime_error.

#include <gseg/map/map_builder.hpp>

#include <string>

namespace gseg::map {

std::string encodeScanJob(const ScanJob& job);
ScanJob decodeScanJob(const std::string& bytes);
std::string encodeScanResult(const ScanResult& result);
/// A scan's failure, as the reply in place of its result.
std::string encodeScanError(const std::string& message);
/// The result; throws std::runtime_error with the worker's message when the bytes say the scan failed.
ScanResult decodeScanResult(const std::string& bytes);

}  // namespace gseg::map
