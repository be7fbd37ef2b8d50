#pragma once
/// \file bytes.hpp
/// Plain values as a byte string and back: the messages between the ranks of a tool run
/// (ranks.hpp). Little-endian whatever the machine; a reader throws on a short message.

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

namespace gseg::tools {

class ByteWriter {
public:
    ByteWriter& u64(std::uint64_t v) {
        for (int i = 0; i < 8; ++i) bytes_.push_back(char((v >> (8 * i)) & 0xFF));
        return *this;
    }
    ByteWriter& f64(double v) {
        std::uint64_t bits = 0;
        std::memcpy(&bits, &v, sizeof bits);
        return u64(bits);
    }
    ByteWriter& str(const std::string& s) {
        u64(s.size());
        bytes_ += s;
        return *this;
    }
    const std::string& bytes() const { return bytes_; }

private:
    std::string bytes_;
};

class ByteReader {
public:
    explicit ByteReader(const std::string& bytes) : bytes_(bytes) {}
    std::uint64_t u64() {
        need(8);
        std::uint64_t v = 0;
        for (int i = 0; i < 8; ++i) v |= std::uint64_t(static_cast<unsigned char>(bytes_[pos_ + std::size_t(i)])) << (8 * i);
        pos_ += 8;
        return v;
    }
    double f64() {
        const std::uint64_t bits = u64();
        double v = 0;
        std::memcpy(&v, &bits, sizeof v);
        return v;
    }
    std::string str() {
        const std::uint64_t n = u64();
        need(n);
        std::string s = bytes_.substr(pos_, std::size_t(n));
        pos_ += std::size_t(n);
        return s;
    }
    bool done() const { return pos_ == bytes_.size(); }

private:
    void need(std::uint64_t n) const {
        if (n > bytes_.size() - pos_) throw std::runtime_error("message between processes truncated");
    }
    const std::string& bytes_;
    std::size_t pos_ = 0;
};

}  // namespace gseg::tools
