#pragma once
// Checks of the command lines' numbers (the drench command, the playground demo, the benchmarks), written
// once: CLI11's own checks let "1e308" through to a conversion and name their ranges' bounds as 309-digit
// numbers.

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdlib>
#include <string>

namespace drench::cli {

/// `message` with every word (a run of non-blank characters) over 40 characters cut to its first 24 and its
/// length: a 309-digit number or a pasted scene must not fill the terminal, and the start tells which it was.
inline std::string shorten_long_words(const std::string& message) {
  constexpr std::size_t kLongest = 40, kKept = 24;
  std::string shortened, word;
  auto flush = [&] {
    if (word.size() > kLongest) {
      shortened += word.substr(0, kKept) + "...(" + std::to_string(word.size()) + " characters)";
    } else {
      shortened += word;
    }
    word.clear();
  };
  for (const char c : message) {
    if (c == ' ' || c == '\n' || c == '\t') {
      flush();
      shortened += c;
    } else {
      word += c;
    }
  }
  flush();
  return shortened;
}

/// `text` as a message quotes it: up to 40 characters whole, else its first 24 and its length.
inline std::string quoted_argument(const std::string& text) {
  return "'" + shorten_long_words(text) + "'";
}

/// A check of a whole number in [low, high] written as decimal digits. CLI11's own checks let "1e308"
/// through to the conversion, saturate a 309-digit number to the largest integer, and print the bound of
/// their range as a 309-digit number.
inline CLI::Validator whole_number(unsigned long long low, unsigned long long high) {
  const std::string range = "[" + std::to_string(low) + ", " + std::to_string(high) + "]";
  return CLI::Validator(
      [low, high, range](std::string& text) -> std::string {
        // 19 digits always fit an unsigned 64-bit integer; the bounds here are below 2^63.
        if (text.empty() || text.size() > 19 || text.find_first_not_of("0123456789") != std::string::npos ||
            std::stoull(text) < low || std::stoull(text) > high)
          return "must be a whole number in " + range + ", got " + quoted_argument(text);
        return "";
      },
      "INT in " + range);
}

/// A check of a finite number >= 0, e.g. a time in seconds.
inline CLI::Validator non_negative_number() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        if (text.empty() || *end != '\0' || !std::isfinite(value) || value < 0)
          return "must be a finite number >= 0, got " + quoted_argument(text);
        return "";
      },
      "NUMBER >= 0");
}

/// A check of a finite number > 0, e.g. a spacing in metres.
inline CLI::Validator finite_positive() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        if (text.empty() || *end != '\0' || !std::isfinite(value) || value <= 0)
          return "must be a finite number > 0, got " + quoted_argument(text);
        return "";
      },
      "NUMBER > 0");
}

/// A check that a text option is not empty: where "" means "not given" inside drench (render's --camera and
/// --out, sweep's --reference), an empty argument would be silently ignored.
inline CLI::Validator non_empty() {
  return CLI::Validator(
      [](std::string& text) -> std::string { return text.empty() ? "must not be empty" : ""; }, "TEXT");
}

}  // namespace drench::cli
