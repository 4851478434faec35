-- Shared by the scripts that end a job: state, error, expiry (and the "done" message), and the
-- entry acknowledged.
-- KEYS: hash, input, stream.  ARGV (of the caller) give: now_ms, ttl_ms, entry id, group.
local function drop(stream, group, entry)
  redis.call('XACK', stream, group, entry)
  redis.call('XDEL', stream, entry)
end
-- A client's share (decision 78): <prefix>client:<client>, a sorted set of its jobs that hold a
-- slot, scored by when that ends (kUnfinished while queued or running; finished_ms + ttl once
-- finished); a downloaded result or a cancelled job leaves it. It expires with its last job.
local kUnfinished = 9e15
local function job_id(hash) return string.match(hash, 'job:(%x+)$') end
local function expire_share(client)
  local top = redis.call('ZRANGE', client, -1, -1, 'WITHSCORES')
  if not top[2] then redis.call('DEL', client)
  elseif tonumber(top[2]) < kUnfinished then redis.call('PEXPIREAT', client, top[2]) end
end
local function leave_share(hash)
  local client = redis.call('HGET', hash, 'client')
  if not client then return end
  redis.call('ZREM', client, job_id(hash))
  expire_share(client)
end
local function expire_job(hash, ttl_ms)
  redis.call('PEXPIRE', hash, ttl_ms)
  local client = redis.call('HGET', hash, 'client')
  if client then
    if redis.call('HGET', hash, 'state') == 'cancelled' then
      leave_share(hash)
    else
      local until_ms = tonumber(redis.call('HGET', hash, 'finished_ms')) + tonumber(ttl_ms)
      redis.call('ZADD', client, 'XX', string.format('%d', until_ms), job_id(hash))
      expire_share(client)
    end
  end
  local idem = redis.call('HGET', hash, 'idem')
  if idem then redis.call('PEXPIRE', idem, ttl_ms) end
  -- Every replica's long polls (GET /v1/jobs/{id}?wait=) learn that the job finished.
  local prefix, id = string.match(hash, '^(.*)job:(%x+)$')
  if prefix then redis.call('PUBLISH', prefix .. 'done', id) end
end
