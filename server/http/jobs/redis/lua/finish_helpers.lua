-- Shared by the scripts that end a job: state, error, expiry (and the "done" message), and the
-- entry acknowledged.
-- KEYS: hash, input, stream.  ARGV (of the caller) give: now_ms, ttl_ms, entry id, group.
local function drop(stream, group, entry)
  redis.call('XACK', stream, group, entry)
  redis.call('XDEL', stream, entry)
end
local function expire_job(hash, ttl_ms)
  redis.call('PEXPIRE', hash, ttl_ms)
  local idem = redis.call('HGET', hash, 'idem')
  if idem then redis.call('PEXPIRE', idem, ttl_ms) end
  -- Every replica's long polls (GET /v1/jobs/{id}?wait=) learn that the job finished.
  local prefix, id = string.match(hash, '^(.*)job:(%x+)$')
  if prefix then redis.call('PUBLISH', prefix .. 'done', id) end
end
