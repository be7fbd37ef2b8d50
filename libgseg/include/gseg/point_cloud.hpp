#pragma once
/// \file point_cloud.hpp
/// Non-owning view over x, y, z float triples laid out with a fixed stride.

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace gseg {

/// Read-only view over N points whose x, y, z are three consecutive floats that repeat every
/// `strideBytes` bytes. A KITTI buffer (x, y, z, intensity) is viewed with a stride of 16 bytes and
/// is never copied. The viewed memory must outlive the view.
class PointCloudView {
public:
    PointCloudView() = default;

    /// \param xyz         address of the first point's x
    /// \param size        number of points
    /// \param strideBytes bytes from one point's x to the next point's x (>= 12)
    PointCloudView(const float* xyz, std::size_t size, std::size_t strideBytes = 3 * sizeof(float))
        : base_(reinterpret_cast<const std::uint8_t*>(xyz)), size_(size), stride_(strideBytes) {}

    std::size_t size() const { return size_; }
    bool empty() const { return size_ == 0; }
    std::size_t strideBytes() const { return stride_; }

    /// Pointer to the x, y, z of point i (no bounds check).
    const float* point(std::size_t i) const {
        return reinterpret_cast<const float*>(base_ + i * stride_);
    }
    float x(std::size_t i) const { return point(i)[0]; }
    float y(std::size_t i) const { return point(i)[1]; }
    float z(std::size_t i) const { return point(i)[2]; }

private:
    const std::uint8_t* base_ = nullptr;
    std::size_t size_ = 0;
    std::size_t stride_ = 3 * sizeof(float);
};

}  // namespace gseg
