-- Accepting a job: the hash, the idempotency key and the stream entry, or why not. The input
-- itself is SET (with an expiry, in case this script never runs) just before, in the same
-- pipeline: a payload passed through Lua costs about 2 ms per MB more than a plain SET. An
-- accepted job's input loses the expiry; a refused one's is deleted.
-- With a client key (finish_helpers.lua), at most client_quota of its jobs may hold a slot.
-- Returns {'ok', entries waiting before this one}, {'full', waiting}, {'reused'},
-- {'replay', earlier job id}, {'noinput'} (the SET did not happen) or {'over', jobs the client
-- keeps, when its first slot frees (ms, kUnfinished if none is finished)}.
local function submit(hash, input_key, stream, idem, id, input_bytes, format, params, created_ms, capacity, fingerprint,
                      group, has_key, job_prefix, client, client_quota)
  if redis.call('EXISTS', input_key) == 0 then return {'noinput'} end
  if has_key == '1' then
    local prev = redis.call('GET', idem)
    if prev then
      local bar = string.find(prev, '|', 1, true)
      local jid = string.sub(prev, 1, bar - 1)
      if string.sub(prev, bar + 1) ~= fingerprint then redis.call('DEL', input_key) return {'reused'} end
      if redis.call('EXISTS', job_prefix .. jid) == 1 then redis.call('DEL', input_key) return {'replay', jid} end
    end
  end
  if redis.call('EXISTS', stream) == 0 then
    redis.call('XGROUP', 'CREATE', stream, group, '0', 'MKSTREAM')
  end
  local waiting = redis.call('XLEN', stream) - redis.call('XPENDING', stream, group)[1]
  if waiting >= tonumber(capacity) then redis.call('DEL', input_key) return {'full', waiting} end
  if client ~= '' then
    redis.call('ZREMRANGEBYSCORE', client, '-inf', created_ms)
    local held = redis.call('ZCARD', client)
    if held >= tonumber(client_quota) then
      redis.call('DEL', input_key)
      return {'over', held, redis.call('ZRANGE', client, 0, 0, 'WITHSCORES')[2]}
    end
    redis.call('ZADD', client, string.format('%d', kUnfinished), id)
    redis.call('PERSIST', client)
    redis.call('HSET', hash, 'client', client)
  end
  redis.call('HSET', hash, 'state', 'queued', 'stage', 'queued', 'fraction', '0', 'format', format,
             'params', params, 'created_ms', created_ms, 'input_bytes', input_bytes, 'attempts', '0')
  redis.call('PERSIST', input_key)
  if has_key == '1' then
    redis.call('SET', idem, id .. '|' .. fingerprint)
    redis.call('HSET', hash, 'idem', idem)
  end
  redis.call('XADD', stream, '*', 'id', id)
  return {'ok', waiting}
end
