/// ccd_fuzz_input: converts between fuzz_ccd inputs (ccd_fuzz_input.hpp) and readable queries.
///
///   ccd_fuzz_input decode FILE...                  one line per file: its 24 coordinates (%.17g), in the
///                                                   order p_t0 a_t0 b_t0 c_t0 p_t1 a_t1 b_t1 c_t1
///   ccd_fuzz_input encode [FLAGS [ARGUMENT...]]    reads one query from standard input and writes its
///                                                   encoding to standard output
///
/// encode takes either 24 numbers or a line of a ccd-vertex-face `.vf.txt` file (qid, truth, 24 rationals,
/// 24 doubles: the last 24 fields are used). FLAGS and ARGUMENTs are the structure byte and its argument
/// bytes (decimal or 0x hex). Built with the fuzz targets; used to make fuzz/corpus/ccd.

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "ccd_fuzz_input.hpp"

namespace {

int usage() {
  std::fprintf(stderr,
               "usage: ccd_fuzz_input decode FILE...\n"
               "       ccd_fuzz_input encode [FLAGS [ARGUMENT...]] < query > input\n");
  return 2;
}

int decode(int argc, char** argv) {
  for (int i = 2; i < argc; ++i) {
    std::ifstream file(argv[i], std::ios::binary);
    if (!file) {
      std::fprintf(stderr, "ccd_fuzz_input: cannot read %s\n", argv[i]);
      return 1;
    }
    const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(file)),
                                          std::istreambuf_iterator<char>());
    const auto x = drench::fuzz::query_coordinates(drench::fuzz::decode_query(bytes.data(), bytes.size()));
    for (int k = 0; k < 24; ++k)
      std::printf("%.17g%c", x[k], k == 23 ? '\n' : ' ');
  }
  return 0;
}

bool parse_byte(const char* text, std::uint8_t& out) {
  char* end = nullptr;
  const long value = std::strtol(text, &end, 0);
  if (end == text || *end != '\0' || value < 0 || value > 255) return false;
  out = static_cast<std::uint8_t>(value);
  return true;
}

int encode(int argc, char** argv) {
  std::uint8_t flags = 0;
  std::vector<std::uint8_t> arguments;
  for (int i = 2; i < argc; ++i) {
    std::uint8_t byte = 0;
    if (!parse_byte(argv[i], byte)) {
      std::fprintf(stderr, "ccd_fuzz_input: not a byte: %s\n", argv[i]);
      return 2;
    }
    if (i == 2) {
      flags = byte;
    } else {
      arguments.push_back(byte);
    }
  }
  std::string line;
  std::getline(std::cin, line);
  std::vector<std::string> fields;
  std::istringstream words(line);
  for (std::string word; words >> word;)
    fields.push_back(word);
  if (fields.size() != 24 && fields.size() != 50) {
    std::fprintf(stderr,
                 "ccd_fuzz_input: expected 24 numbers or a .vf.txt line (50 fields), got %zu fields\n",
                 fields.size());
    return 1;
  }
  std::array<double, 24> x{};
  const std::size_t first = fields.size() - 24;
  for (std::size_t k = 0; k < 24; ++k) {
    const char* text = fields[first + k].c_str();
    char* end = nullptr;
    x[k] = std::strtod(text, &end);
    if (end == text || *end != '\0') {
      std::fprintf(stderr, "ccd_fuzz_input: not a number: %s\n", text);
      return 1;
    }
  }
  const auto bytes = drench::fuzz::encode_coordinates(x, flags, arguments);
  if (flags == 0) {
    const auto back = drench::fuzz::query_coordinates(drench::fuzz::decode_query(bytes.data(), bytes.size()));
    for (int k = 0; k < 24; ++k) {
      if (std::memcmp(&back[k], &x[k], sizeof(double)) != 0) {
        std::fprintf(stderr,
                     "ccd_fuzz_input: coordinate %d (%.17g) does not round-trip (exponent beyond 2^%d)\n", k,
                     x[k], drench::fuzz::kRawExponentLimit);
        return 1;
      }
    }
  }
  std::fwrite(bytes.data(), 1, bytes.size(), stdout);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage();
  const std::string command = argv[1];
  if (command == "decode") return decode(argc, argv);
  if (command == "encode") return encode(argc, argv);
  return usage();
}
