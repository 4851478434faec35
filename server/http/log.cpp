#include "server/http/log.h"

#include <spdlog/sinks/stdout_sinks.h>

namespace mdn::http {

EventLog::EventLog(const ServerConfig& config)
    : logger_(std::make_shared<spdlog::logger>("meshdenoise-server",
                                               std::make_shared<spdlog::sinks::stderr_sink_mt>())),
      format_(config.log_format) {
  if (format_ == LogFormat::Json) {
    // %v is the rest of one JSON object, written by log() below.
    logger_->set_pattern(R"({"time":"%Y-%m-%dT%H:%M:%S.%f%z","level":"%l",%v})");
  } else {
    logger_->set_pattern("%Y-%m-%dT%H:%M:%S.%e %l %v");
  }
  logger_->set_level(spdlog::level::from_str(config.log_level));
  logger_->flush_on(spdlog::level::trace);  // line-buffered: logs are read live by operators and tests
}

void EventLog::log(spdlog::level::level_enum level, std::string_view event, const nlohmann::json& fields) const {
  if (!logger_->should_log(level)) return;
  if (format_ == LogFormat::Json) {
    nlohmann::json j = nlohmann::json::object();
    j["event"] = event;
    if (fields.is_object()) j.update(fields);
    std::string body = j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    logger_->log(level, "{}", std::string_view(body).substr(1, body.size() - 2));
  } else {
    std::string line(event);
    if (fields.is_object()) {
      for (const auto& [key, value] : fields.items()) {
        line += ' ';
        line += key;
        line += '=';
        const bool bare = value.is_string() && value.get_ref<const std::string&>().find_first_of(" \"=\n") == std::string::npos &&
                          !value.get_ref<const std::string&>().empty();
        line += bare ? value.get<std::string>() : value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
      }
    }
    logger_->log(level, "{}", line);
  }
}

}  // namespace mdn::http
