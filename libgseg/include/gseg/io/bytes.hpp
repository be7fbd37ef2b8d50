#pragma once
/// \file bytes.hpp
/// Plain values as a byte string and back: the one byte coding of gseg's wire formats (the
/// messages between the ranks of a tool run, a scan's map update, a scan sent to a worker).
/// Little-endian whatever the machine; varints are LEB128 (7 bits a byte, low first). A reader
/// throws std::runtime_error "<what>: truncated" on a short message and "<what>: malformed number"
/// on a varint longer than 64 bits.

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

namespace gseg::io {

class ByteWriter {
public:
    ByteWriter& u64(std::uint64_t v) {
        char b[8];
        for (int i = 0; i < 8; ++i) b[i] = char((v >> (8 * i)) & 0xFF);
        bytes_.append(b, 8);
        return *this;
    }
    ByteWriter& u8(std::uint8_t v) {
        bytes_.push_back(char(v));
        return *this;
    }
    ByteWriter& u32(std::uint32_t v) {
        for (int i = 0; i < 4; ++i) bytes_.push_back(char((v >> (8 * i)) & 0xFF));
        return *this;
    }
    ByteWriter& f64(double v) {
        std::uint64_t bits = 0;
        std::memcpy(&bits, &v, sizeof bits);
        return u64(bits);
    }
    ByteWriter& f32(float v) {
        std::uint32_t bits = 0;
        std::memcpy(&bits, &v, sizeof bits);
        return u32(bits);
    }
    ByteWriter& varint(std::uint64_t v) {
        while (v >= 0x80) bytes_.push_back(char(std::uint8_t(v) | 0x80)), v >>= 7;
        bytes_.push_back(char(v));
        return *this;
    }
    /// The length (u64), then the bytes.
    ByteWriter& str(const std::string& s) {
        u64(s.size());
        bytes_ += s;
        return *this;
    }
    /// The bytes as they are (a magic, a header).
    ByteWriter& raw(const char* data, std::size_t n) {
        bytes_.append(data, n);
        return *this;
    }
    const std::string& bytes() const { return bytes_; }
    std::string take() { return std::move(bytes_); }

private:
    std::string bytes_;
};

class ByteReader {
public:
    /// Reads `bytes` (kept by reference) from `start`; `what` names them in errors.
    explicit ByteReader(const std::string& bytes, std::string what = "message between processes", std::size_t start = 0)
        : bytes_(bytes), what_(std::move(what)), pos_(start) {}
    std::uint64_t u64() {
        need(8);
        std::uint64_t v = 0;
        for (int i = 0; i < 8; ++i) v |= std::uint64_t(static_cast<unsigned char>(bytes_[pos_ + std::size_t(i)])) << (8 * i);
        pos_ += 8;
        return v;
    }
    std::uint8_t u8() {
        need(1);
        return std::uint8_t(bytes_[pos_++]);
    }
    std::uint32_t u32() {
        need(4);
        std::uint32_t v = 0;
        for (int i = 0; i < 4; ++i) v |= std::uint32_t(static_cast<unsigned char>(bytes_[pos_ + std::size_t(i)])) << (8 * i);
        pos_ += 4;
        return v;
    }
    double f64() {
        const std::uint64_t bits = u64();
        double v = 0;
        std::memcpy(&v, &bits, sizeof v);
        return v;
    }
    float f32() {
        const std::uint32_t bits = u32();
        float v = 0;
        std::memcpy(&v, &bits, sizeof v);
        return v;
    }
    std::uint64_t varint() {
        std::uint64_t v = 0;
        for (int shift = 0; shift < 64; shift += 7) {
            need(1);
            const std::uint8_t b = std::uint8_t(bytes_[pos_++]);
            v |= std::uint64_t(b & 0x7f) << shift;
            if (!(b & 0x80)) return v;
        }
        throw std::runtime_error(what_ + ": malformed number");
    }
    std::string str() {
        const std::uint64_t n = u64();
        need(n);
        std::string s = bytes_.substr(pos_, std::size_t(n));
        pos_ += std::size_t(n);
        return s;
    }
    std::size_t remaining() const { return bytes_.size() - pos_; }
    bool done() const { return pos_ == bytes_.size(); }

private:
    void need(std::uint64_t n) const {
        if (n > bytes_.size() - pos_) throw std::runtime_error(what_ + ": truncated");
    }
    const std::string& bytes_;
    std::string what_;
    std::size_t pos_ = 0;
};

}  // namespace gseg::io
