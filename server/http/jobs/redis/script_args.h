// One typed argument struct per Lua script (lua/*.lua); its to_argv() builds the whole EVAL
// command (the script text with the fragments it needs, the KEYS count, KEYS, ARGV) and is the
// only place where a position of KEYS or ARGV is written. Field names follow the scripts'
// headers. Plain values: build one per call, on any thread.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace mdn::http::redis {

using Argv = std::vector<std::string>;
// For Connection::checked and checked_pipeline; the views point into `argv`.
std::vector<std::string_view> views(const Argv& argv);

// What every start of a job needs (lua/start_job.lua: ARGV[1] to ARGV[10]).
struct StartFields {
  std::string consumer, now_ms, max_attempts, group, exhausted_problem, cancelled_problem, ttl_ms, lost_problem,
      job_prefix;
};

// A new job's hash fields (lua/submit_job.lua).
struct SubmitFields {
  std::string id, input_length, format, params, created_ms, capacity, fingerprint, has_key;
  std::string client, client_quota;  // the client's share key ("" for none) and its quota
};

struct SubmitArgs {  // lua/submit.lua
  std::string hash, input, stream, idem;
  SubmitFields job;
  std::string group, job_prefix;
  Argv to_argv() const;
};

struct SubmitStartArgs {  // lua/submit_start.lua
  std::string stream, hash, input, idem;
  StartFields start;
  SubmitFields job;
  Argv to_argv() const;
};

struct TakeArgs {  // lua/take.lua
  std::string stream;
  StartFields start;
  Argv to_argv() const;
};

struct StartArgs {  // lua/start.lua: an entry taken over with XAUTOCLAIM
  std::string stream;
  StartFields start;
  std::string entry_id, job_id;
  Argv to_argv() const;
};

struct BeatArgs {  // lua/beat.lua
  std::string hash, stream, consumer, stage /* "" = unchanged */, fraction, entry_id, group;
  Argv to_argv() const;
};

struct CheckArgs {  // lua/check.lua
  std::string hash, consumer;
  Argv to_argv() const;
};

struct FinishArgs {  // lua/finish.lua
  std::string hash, input, stream, result, staged_result, consumer, state, problem, summary, ttl_ms, now_ms,
      entry_id, group, output_bytes;
  Argv to_argv() const;
};

struct ReleaseArgs {  // lua/release.lua
  std::string hash, stream, consumer, entry_id, group, job_id;
  Argv to_argv() const;
};

struct CancelArgs {  // lua/cancel.lua
  std::string hash, input, result, problem, now_ms, ttl_ms;
  Argv to_argv() const;
};

struct FetchedArgs {  // lua/fetched.lua
  std::string hash;
  Argv to_argv() const;
};

struct ForgetConsumersArgs {  // lua/forget_consumers.lua
  std::string stream, group, idle_ms;
  Argv to_argv() const;
};

}  // namespace mdn::http::redis
