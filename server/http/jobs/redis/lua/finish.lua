-- A succeeded job's result is SET (with the results' expiry) under this consumer's own staging
-- key just before, in the same pipeline, and renamed here: a payload passed through Lua costs
-- about 2 ms per MB more, and a replica that lost the job never overwrites the owner's result.
-- KEYS: hash, input, stream, result, staged result.  ARGV: consumer, state, problem, output
-- summary, (unused), ttl_ms, now_ms, entry id, group, output_bytes.
if redis.call('HGET', KEYS[1], 'owner') ~= ARGV[1] or redis.call('HGET', KEYS[1], 'state') ~= 'running' then
  redis.call('DEL', KEYS[5])
  return 'stale'
end
if ARGV[2] == 'succeeded' then
  if redis.call('EXISTS', KEYS[5]) == 0 then return redis.error_reply('the staged result is missing') end
  redis.call('RENAME', KEYS[5], KEYS[4])
  redis.call('HSET', KEYS[1], 'output', ARGV[4], 'output_bytes', ARGV[10], 'stage', 'done', 'fraction', '1')
else
  redis.call('HSET', KEYS[1], 'error', ARGV[3])
end
redis.call('HSET', KEYS[1], 'state', ARGV[2], 'finished_ms', ARGV[7])
redis.call('DEL', KEYS[2])
expire_job(KEYS[1], ARGV[6])
drop(KEYS[3], ARGV[9], ARGV[8])
return 'ok'
