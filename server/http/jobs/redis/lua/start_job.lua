-- Starting a job, shared by take.lua and start.lua (prepended to both by store.cpp). KEYS: stream.  ARGV: consumer, now_ms,
-- max_attempts, (unused), group, exhausted problem, cancelled problem, ttl_ms, lost-input
-- problem, job key prefix, (start.lua: entry id, job id).
-- Returns {outcome, attempt, previous owner, input, format, params, entry id, job id}.
local function start_job(entry, jid, want_input)
  local hash = ARGV[10] .. jid
  local input_key = hash .. ':input'
  local function finish(state, problem)
    redis.call('HSET', hash, 'state', state, 'error', problem, 'finished_ms', ARGV[2])
    redis.call('DEL', input_key)
    expire_job(hash, ARGV[8])
    drop(KEYS[1], ARGV[5], entry)
  end
  local function result(outcome, n, previous)
    return {outcome, n or 0, previous or '', '', '', '', entry, jid}
  end
  local st = redis.call('HGET', hash, 'state')
  if not st then drop(KEYS[1], ARGV[5], entry) return result('gone') end
  if st == 'succeeded' or st == 'failed' or st == 'cancelled' then drop(KEYS[1], ARGV[5], entry) return result('done') end
  if redis.call('HGET', hash, 'cancel') == '1' then finish('cancelled', ARGV[7]) return result('cancelled') end
  local previous = redis.call('HGET', hash, 'owner') or ''
  local n = redis.call('HINCRBY', hash, 'attempts', 1)
  if n > tonumber(ARGV[3]) then
    redis.call('HINCRBY', hash, 'attempts', -1)
    finish('failed', ARGV[6])
    return result('exhausted', n - 1, previous)
  end
  local input = ''
  if want_input then
    input = redis.call('GET', input_key)
    if not input then finish('failed', ARGV[9]) return result('lost') end
  elseif redis.call('EXISTS', input_key) == 0 then
    finish('failed', ARGV[9]) return result('lost')
  end
  redis.call('HSET', hash, 'state', 'running', 'owner', ARGV[1], 'started_ms', ARGV[2], 'stage', 'decode',
             'fraction', '0')
  return {'run', n, previous, input, redis.call('HGET', hash, 'format'), redis.call('HGET', hash, 'params'), entry, jid}
end
local function start_entry(e, want_input)
  local jid = ''
  for i = 1, #e[2], 2 do
    if e[2][i] == 'id' then jid = e[2][i + 1] end
  end
  return start_job(e[1], jid, want_input)
end
