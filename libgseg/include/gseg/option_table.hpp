#pragma once
/// \file option_table.hpp
/// The key table of an options struct: one row per field (its name, the key of YAML and INI files,
/// its unit and meaning), and reading a field from text or writing it as text. gseg::Params,
/// gseg::SensorHeightOptions and gseg::map::TraversabilityOptions are set through one each, so every
/// configuration route (YAML, INI, the MRPT plugin) accepts the same keys and values.

#include <gseg/text.hpp>

#include <cstdint>
#include <limits>
#include <locale>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace gseg {

/// Throws std::invalid_argument "<what> '<key>' = <value> is invalid: <why>" unless `ok`: the one
/// message of every options struct's validate().
inline void requireOption(bool ok, const char* what, const char* key, double value, const char* why) {
    if (ok) return;
    std::ostringstream msg;
    msg << what << " '" << key << "' = " << value << " is invalid: " << why;
    throw std::invalid_argument(msg.str());
}

/// One key of an options struct S.
template <class S>
struct OptionKey {
    using Field = std::variant<double S::*, int S::*, std::uint64_t S::*, bool S::*>;
    const char* name;          ///< the field's name, also its key in configuration files
    Field field;
    const char* unit = "";     ///< e.g. "m", "deg", "points", "-" (none)
    const char* meaning = "";  ///< one line
};

/// The keys of an options struct S, and the one way to set and get its fields by name.
template <class S>
class OptionTable {
public:
    /// `what` names a key in messages: "parameter" gives "unknown parameter 'x'".
    OptionTable(const char* what, std::vector<OptionKey<S>> rows) : what_(what), rows_(std::move(rows)) {
        for (const auto& r : rows_) names_.emplace_back(r.name);
    }

    const std::vector<OptionKey<S>>& rows() const { return rows_; }
    const std::vector<std::string>& names() const { return names_; }  ///< in table order

    /// Throws std::invalid_argument on an unknown key or a value that is not one of the field's
    /// type (numbers as gseg::parseNumber reads them, surrounding blanks allowed; bools true/false/1/0).
    void set(S& s, const std::string& key, const std::string& value) const {
        std::visit([&](auto member) { s.*member = parse<std::remove_reference_t<decltype(s.*member)>>(key, value); },
                   find(key).field);
    }

    /// The field as text that set() reads back to the same value (doubles with 17 digits).
    std::string get(const S& s, const std::string& key) const {
        std::ostringstream out;
        out.imbue(std::locale::classic());
        out.precision(std::numeric_limits<double>::max_digits10);
        std::visit([&](auto member) { out << std::boolalpha << s.*member; }, find(key).field);
        return out.str();
    }

    /// {unit, meaning} of a key; throws std::invalid_argument on an unknown one.
    std::pair<std::string, std::string> describe(const std::string& key) const {
        const OptionKey<S>& r = find(key);
        return {r.unit, r.meaning};
    }

private:
    const OptionKey<S>& find(const std::string& key) const {
        for (const auto& r : rows_)
            if (key == r.name) return r;
        throw std::invalid_argument("unknown " + what_ + " '" + key + "'");
    }

    template <typename T>
    T parse(const std::string& key, const std::string& text) const {
        if constexpr (std::is_same_v<T, bool>) {
            const std::string t = trim(text);
            if (t == "true" || t == "1") return true;
            if (t == "false" || t == "0") return false;
            throw std::invalid_argument(what_ + " '" + key + "': cannot read '" + text + "' as true or false");
        } else {
            const std::optional<T> v = parseNumber<T>(text);
            if (!v)
                throw std::invalid_argument(what_ + " '" + key + "': cannot read '" + text + "' as a " +
                                            (std::is_floating_point_v<T> ? "number" : "whole number"));
            return *v;
        }
    }

    std::string what_;
    std::vector<OptionKey<S>> rows_;
    std::vector<std::string> names_;
};

}  // namespace gseg
