#include "server/http/jobs/redis/scripts.h"

#include <stdexcept>

namespace mdn::http::redis {

std::string lua_script(std::string_view name) {
  for (const embedded::File& f : embedded::lua_scripts())
    if (f.path == name) return std::string(f.bytes);
  throw std::logic_error("no Lua script lua/" + std::string(name) + ".lua");
}

}  // namespace mdn::http::redis
