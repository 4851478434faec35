#include "server/http/routes/api_keys.h"

#include <openssl/evp.h>
#include <openssl/hmac.h>

#include <stdexcept>

#include "server/http/routes/http_support.h"

namespace mdn::http {
namespace {

constexpr std::size_t kTagHexDigits = 32;  // 128 bits of HMAC-SHA256

std::string tag(const std::string& key, const std::string& store_id) {
  unsigned char mac[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (HMAC(EVP_sha256(), key.data(), static_cast<int>(key.size()), reinterpret_cast<const unsigned char*>(store_id.data()),
           store_id.size(), mac, &length) == nullptr)
    throw std::runtime_error("HMAC-SHA256 failed");
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < length && out.size() < kTagHexDigits; ++i) {
    out += kHex[mac[i] >> 4];
    out += kHex[mac[i] & 15];
  }
  return out;
}

}  // namespace

std::string bearer_token(const std::string& authorization) {
  const std::string prefix = "bearer ";
  if (authorization.size() < prefix.size() || lower(authorization.substr(0, prefix.size())) != prefix) return {};
  return trim(authorization.substr(prefix.size()));
}

bool equal_secrets(const std::string& a, const std::string& b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (std::size_t i = 0; i < b.size(); ++i) diff |= static_cast<unsigned char>(b[i] ^ (i < a.size() ? a[i] : 0));
  return diff == 0;
}

const ApiKey* ClientKeys::client(const std::string& authorization) const {
  const std::string token = bearer_token(authorization);
  const ApiKey* found = nullptr;
  for (const ApiKey& k : keys_)  // no early exit: the time does not tell which key matched
    if (equal_secrets(token, k.key) && !token.empty()) found = &k;
  return found;
}

std::string ClientKeys::public_id(const ApiKey& client, const std::string& store_id) const {
  return store_id + tag(client.key, store_id);
}

std::optional<std::string> ClientKeys::store_id(const ApiKey& client, const std::string& public_id) const {
  if (public_id.size() <= kTagHexDigits) return std::nullopt;
  const std::string id = public_id.substr(0, public_id.size() - kTagHexDigits);
  if (!equal_secrets(public_id.substr(id.size()), tag(client.key, id))) return std::nullopt;
  return id;
}

}  // namespace mdn::http
