// The store's Lua scripts, one per file in lua/ (each file's header names its KEYS and ARGV),
// embedded at build time (server/http/embed_files.cmake). Each is one atomic step of a job's
// life; store.cpp concatenates the shared fragments (finish_helpers, start_job, submit_job)
// before the scripts that call them.
#pragma once

#include <span>
#include <string>
#include <string_view>

#include "server/http/embedded.h"

namespace mdn::http::embedded {

std::span<const File> lua_scripts();  // every lua/<name>.lua, under <name>

}  // namespace mdn::http::embedded

namespace mdn::http::redis {

// The text of lua/<name>.lua; throws std::logic_error for a name that is not there.
std::string lua_script(std::string_view name);

}  // namespace mdn::http::redis
