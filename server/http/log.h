// Structured logs: one event name plus fields. Text mode prints "event k=v ...", JSON mode
// one object per line ({"time":..., "level":..., "event":..., fields...}) for log shippers.
#pragma once

#include <memory>
#include <string_view>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "server/http/config.h"

namespace mdn::http {

class EventLog {
 public:
  // Writes to stderr in the configured format and level.
  explicit EventLog(const ServerConfig& config);
  // Logs `event` with `fields` (a JSON object). Thread-safe.
  void log(spdlog::level::level_enum level, std::string_view event,
           const nlohmann::json& fields = nlohmann::json::object()) const;
  void info(std::string_view event, const nlohmann::json& fields = nlohmann::json::object()) const {
    log(spdlog::level::info, event, fields);
  }
  void warn(std::string_view event, const nlohmann::json& fields = nlohmann::json::object()) const {
    log(spdlog::level::warn, event, fields);
  }
  void error(std::string_view event, const nlohmann::json& fields = nlohmann::json::object()) const {
    log(spdlog::level::err, event, fields);
  }

 private:
  std::shared_ptr<spdlog::logger> logger_;
  LogFormat format_;
};

}  // namespace mdn::http
