// Identifiers nobody can predict: job ids and this process's request-id prefix come from the
// kernel's CSPRNG (getrandom(2), the source /dev/urandom reads), never from a seeded generator
// (a std::mt19937_64 seeded with 32 bits gave away every id after ~150 of one's own; issue 32).
#pragma once

#include <string>

namespace mdn::http {

// `bytes` random bytes from getrandom(2), as 2 x `bytes` lowercase hex digits. Thread-safe.
// Throws std::runtime_error if the kernel cannot supply them (it blocks only before the
// pool is first seeded, at early boot).
std::string random_hex(int bytes);

// A job id: 128 random bits, 32 hex digits.
inline std::string new_job_id() { return random_hex(16); }

}  // namespace mdn::http
