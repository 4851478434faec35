#include "server/http/jobs/redis/script_args.h"

#include "server/http/jobs/redis/scripts.h"

#include <initializer_list>

namespace mdn::http::redis {
namespace {

// A script with the fragments it calls, in order (each fragment defines local functions).
std::string join(std::initializer_list<std::string_view> names) {
  std::string text;
  for (std::string_view n : names) text += lua_script(n);
  return text;
}

Argv start_argv(const std::string& text, const std::string& stream, const StartFields& f) {
  // ARGV[4] is unused (kept so the positions of start_job.lua stay those of its header).
  return {"EVAL", text, "1", stream, f.consumer, f.now_ms, f.max_attempts, "", f.group, f.exhausted_problem,
          f.cancelled_problem, f.ttl_ms, f.lost_problem, f.job_prefix};
}

}  // namespace

std::vector<std::string_view> views(const Argv& argv) { return {argv.begin(), argv.end()}; }

Argv SubmitArgs::to_argv() const {
  static const std::string text = join({"finish_helpers", "submit_job", "submit"});
  return {"EVAL", text, "4", hash, input, stream, idem, job.id, job.input_length,
          job.format, job.params, job.created_ms, job.capacity, job.fingerprint, group, job.has_key, job_prefix,
          job.client, job.client_quota};
}

Argv SubmitStartArgs::to_argv() const {
  static const std::string text = join({"finish_helpers", "start_job", "submit_job", "submit_start"});
  Argv a = start_argv(text, stream, start);
  a[2] = std::string(1, '4');  // KEYS: stream, hash, input, idem (not = "4": GCC 12 warns falsely, -Wrestrict)
  a.insert(a.begin() + 4, {hash, input, idem});
  a.insert(a.end(), {job.id, job.input_length, job.format, job.params, job.created_ms, job.capacity, job.fingerprint,
                     job.has_key, job.client, job.client_quota});  // ARGV[11] to ARGV[20]
  return a;
}

Argv TakeArgs::to_argv() const {
  static const std::string text = join({"finish_helpers", "start_job", "take"});
  return start_argv(text, stream, start);
}

Argv StartArgs::to_argv() const {
  static const std::string text = join({"finish_helpers", "start_job", "start"});
  Argv a = start_argv(text, stream, start);
  a.insert(a.end(), {entry_id, job_id});  // ARGV[11], ARGV[12]
  return a;
}

Argv BeatArgs::to_argv() const {
  static const std::string text = join({"beat"});
  return {"EVAL", text, "2", hash, stream, consumer, stage, fraction, entry_id, group};
}

Argv CheckArgs::to_argv() const {
  static const std::string text = join({"check"});
  return {"EVAL", text, "1", hash, consumer}; 
}

Argv FinishArgs::to_argv() const {
  static const std::string text = join({"finish_helpers", "finish"});
  // ARGV[5] is unused.
  return {"EVAL", text, "5", hash, input, stream, result, staged_result, consumer,
          state, problem, summary, "", ttl_ms, now_ms, entry_id, group, output_bytes};
}

Argv ReleaseArgs::to_argv() const {
  static const std::string text = join({"finish_helpers", "release"});
  return {"EVAL", text, "2", hash, stream, consumer, entry_id, group, job_id};
}

Argv CancelArgs::to_argv() const {
  static const std::string text = join({"finish_helpers", "cancel"});
  return {"EVAL", text, "3", hash, input, result, problem, now_ms, ttl_ms};
}

Argv FetchedArgs::to_argv() const {
  static const std::string text = join({"finish_helpers", "fetched"});
  return {"EVAL", text, "1", hash};
}

Argv ForgetConsumersArgs::to_argv() const {
  static const std::string text = join({"forget_consumers"});
  return {"EVAL", text, "1", stream, group, idle_ms};
}

}  // namespace mdn::http::redis
