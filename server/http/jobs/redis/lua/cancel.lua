-- DELETE. KEYS: hash, input, result.  ARGV: cancelled problem, now_ms, ttl_ms.
local st = redis.call('HGET', KEYS[1], 'state')
if not st then return 'none' end
if st == 'queued' then
  redis.call('HSET', KEYS[1], 'cancel', '1', 'state', 'cancelled', 'error', ARGV[1], 'finished_ms', ARGV[2])
  redis.call('DEL', KEYS[2])
  expire_job(KEYS[1], ARGV[3])
  return 'cancelled'
elseif st == 'running' then
  redis.call('HSET', KEYS[1], 'cancel', '1')
  return 'requested'
end
local idem = redis.call('HGET', KEYS[1], 'idem')
leave_share(KEYS[1])
redis.call('DEL', KEYS[1], KEYS[2], KEYS[3])
if idem then redis.call('DEL', idem) end
return 'removed'
