// The server's settings as parse_command_line reads them from flags and an environment given
// as a map (config_test, trusted_proxies_test).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "server/http/config.h"

namespace mdn::http::test {

inline ServerConfig parse(const std::vector<std::string>& args, const std::map<std::string, std::string>& env = {}) {
  return parse_command_line(args, [&](const char* name) -> const char* {
           auto it = env.find(name);
           return it == env.end() ? nullptr : it->second.c_str();
         })
      .config;
}

}  // namespace mdn::http::test
