// Helpers shared by the text readers (ASCII STL, SRE): bounds-checked scanning of a byte
// range with line counting, and strict number parsing.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>

namespace ncrev::io_detail {

inline bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

inline bool iequals(std::string_view a, std::string_view lower_b) {
    if (a.size() != lower_b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
        char c = a[i];
        if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
        if (c != lower_b[i]) return false;
    }
    return true;
}

/// Parses a whole token as a double; false if it is not entirely a number.
inline bool parse_double(std::string_view tok, double& out) {
    if (tok.empty()) return false;
    const char* first = tok.data();
    const char* last = tok.data() + tok.size();
    if (*first == '+') {  // from_chars refuses a leading '+', which some exporters write
        ++first;
        if (first == last || *first == '+' || *first == '-') return false;
    }
    auto [ptr, ec] = std::from_chars(first, last, out, std::chars_format::general);
    return ec == std::errc() && ptr == last;
}

/// Parses a whole token as a float (rounded once, from the decimal text).
inline bool parse_float(std::string_view tok, float& out) {
    if (tok.empty()) return false;
    const char* first = tok.data();
    const char* last = tok.data() + tok.size();
    if (*first == '+') {
        ++first;
        if (first == last || *first == '+' || *first == '-') return false;
    }
    auto [ptr, ec] = std::from_chars(first, last, out, std::chars_format::general);
    return ec == std::errc() && ptr == last;
}

/// Parses a whole token as a decimal integer (no exponent, no point).
inline bool parse_int(std::string_view tok, std::int64_t& out) {
    if (tok.empty()) return false;
    auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), out, 10);
    return ec == std::errc() && ptr == tok.data() + tok.size();
}

/// Shortens a token for an error message.
inline std::string quote(std::string_view tok) {
    constexpr std::size_t kMaxShown = 40;  // enough to recognise, short enough for one line
    std::string s = "'";
    for (std::size_t i = 0; i < tok.size() && i < kMaxShown; ++i) {
        const unsigned char c = static_cast<unsigned char>(tok[i]);
        s += (c >= 0x20 && c < 0x7f) ? static_cast<char>(c) : '?';
    }
    if (tok.size() > kMaxShown) s += "...";
    return s + "'";
}

/// A cursor over text with 1-based line counting. Never reads past `end`.
struct Scanner {
    const char* p;
    const char* end;
    std::int64_t line = 1;

    bool at_end() const { return p >= end; }
    void skip_space() {
        while (p < end && is_space(*p)) {
            if (*p == '\n') ++line;
            ++p;
        }
    }
    /// The next whitespace-delimited token (empty at end of input); `line` is the token's line.
    std::string_view token() {
        skip_space();
        const char* s = p;
        while (p < end && !is_space(*p)) ++p;
        return {s, static_cast<std::size_t>(p - s)};
    }
    /// The rest of the current line, trimmed; consumes the newline.
    std::string_view rest_of_line() {
        while (p < end && (*p == ' ' || *p == '\t')) ++p;
        const char* s = p;
        while (p < end && *p != '\n') ++p;
        const char* e = p;
        while (e > s && is_space(e[-1])) --e;
        return {s, static_cast<std::size_t>(e - s)};
    }
};

}  // namespace ncrev::io_detail
