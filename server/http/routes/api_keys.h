// Per-client ownership of jobs (--api-keys): which client a request comes from, and the job
// ids it sees. With keys, a client's job id is the store's id followed by a tag,
// HMAC-SHA256(client key, store id) cut to 128 bits: any replica that has the same key file
// checks it without asking the store, so the same code serves the memory and the Redis store,
// and an id of another client's job (or a guessed one) is a 404 exactly like a missing job.
// Without keys, ids are the store's (128 random bits, secure_random.h).
//
// Thread-safety: const after construction; every method may be called from any thread.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "server/http/config.h"

namespace mdn::http {

class ClientKeys {
 public:
  explicit ClientKeys(std::vector<ApiKey> keys) : keys_(std::move(keys)) {}
  bool enabled() const { return !keys_.empty(); }
  // The client whose key an "Authorization: Bearer <key>" header carries; nullptr if none.
  // Every key is compared in constant time.
  const ApiKey* client(const std::string& authorization) const;
  // The id `client` sees for the store's job `store_id`: store_id + 32 hex digits of tag.
  std::string public_id(const ApiKey& client, const std::string& store_id) const;
  // The store's id behind `public_id` if that job is `client`'s; nullopt otherwise.
  std::optional<std::string> store_id(const ApiKey& client, const std::string& public_id) const;

 private:
  std::vector<ApiKey> keys_;
};

// "Bearer <token>" -> token (trimmed); empty if the header is not a bearer credential.
std::string bearer_token(const std::string& authorization);
// Compares two secrets in time that depends on their lengths only.
bool equal_secrets(const std::string& a, const std::string& b);

}  // namespace mdn::http
