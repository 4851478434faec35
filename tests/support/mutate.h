// Seeded, deterministic mutation of valid inputs, for the hostile-input tests (files through the
// job path, raw requests through the live server).
#pragma once

#include <algorithm>
#include <cctype>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <iterator>
#include <random>
#include <string>
#include <vector>

namespace mdn::test {

// One deterministic mutant of `bytes`: 1 to 3 of bit flips, a boundary integer written over 4
// bytes (lengths and counts), a truncation, a cut or a repeated slice, and with `text` a number
// swapped for a hostile token (nan, inf, -1, 1e308, ...).
inline std::string mutate(const std::string& bytes, bool text, std::mt19937_64& rng) {
  std::string s = bytes;
  const auto pos = [&](std::size_t n) { return n == 0 ? std::size_t{0} : std::size_t(rng() % n); };
  static const std::uint32_t kWords[] = {0u,          1u,          2u,          3u,          0x7fu,       0x80u,
                                         0xffu,       0x100u,      0x7fffu,     0x8000u,     0xffffu,     0x10000u,
                                         0x7fffffffu, 0x80000000u, 0xfffffffeu, 0xffffffffu, 0x3f800000u, 0x7fc00000u};
  static const char* kTokens[] = {"-1", "0", "nan", "inf", "-inf", "1e308", "4294967296", "99999999999", "-0", "1.5", "2147483648", ""};
  const int steps = 1 + int(rng() % 3);
  for (int step = 0; step < steps && !s.empty(); ++step) {
    switch (rng() % (text ? 6 : 5)) {
      case 0:  // flip bits
        for (int k = 0, n = 1 + int(rng() % 4); k < n; ++k) s[pos(s.size())] ^= char(1u << (rng() % 8));
        break;
      case 1: {  // a boundary integer over 4 bytes (GLB lengths, Draco and accessor counts)
        const std::uint32_t w = kWords[rng() % std::size(kWords)];
        const std::size_t at = pos(s.size() > 4 ? s.size() - 4 : 1);
        for (int k = 0; k < 4 && at + std::size_t(k) < s.size(); ++k) s[at + std::size_t(k)] = char((w >> (8 * k)) & 0xff);
        break;
      }
      case 2:  // truncate
        s.resize(pos(s.size()));
        break;
      case 3: {  // cut a slice
        const std::size_t at = pos(s.size());
        s.erase(at, 1 + rng() % 64);
        break;
      }
      case 4: {  // repeat a slice
        const std::size_t at = pos(s.size());
        s.insert(at, s.substr(at, 1 + rng() % 64));
        break;
      }
      default: {  // text: a number becomes a hostile token
        std::vector<std::size_t> starts;
        for (std::size_t i = 0; i < s.size(); ++i)
          if ((std::isdigit(static_cast<unsigned char>(s[i])) || s[i] == '-') &&
              (i == 0 || !std::isalnum(static_cast<unsigned char>(s[i - 1]))))
            starts.push_back(i);
        if (starts.empty()) break;
        const std::size_t at = starts[pos(starts.size())];
        std::size_t end = at + 1;
        while (end < s.size() && (std::isalnum(static_cast<unsigned char>(s[end])) || s[end] == '.' || s[end] == '-' || s[end] == '+'))
          ++end;
        s.replace(at, end - at, kTokens[rng() % std::size(kTokens)]);
        break;
      }
    }
  }
  return s;
}

// Mutants per seed: `default_count`, or MDN_HOSTILE_MUTANTS=N for deeper local runs (sanitizer
// builds).
inline int mutants_per_seed(int default_count) {
  const char* env = std::getenv("MDN_HOSTILE_MUTANTS");
  return env ? std::max(1, std::atoi(env)) : default_count;
}

}  // namespace mdn::test
