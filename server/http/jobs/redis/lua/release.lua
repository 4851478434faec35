-- A replica stopping with a job still running hands it back at once (not counted as an
-- attempt). KEYS: hash, stream.  ARGV: consumer, entry id, group, job id.
if redis.call('HGET', KEYS[1], 'owner') ~= ARGV[1] or redis.call('HGET', KEYS[1], 'state') ~= 'running' then
  return 'stale'
end
redis.call('HINCRBY', KEYS[1], 'attempts', -1)
redis.call('HSET', KEYS[1], 'state', 'queued', 'stage', 'queued', 'fraction', '0')
redis.call('HDEL', KEYS[1], 'owner')
drop(KEYS[2], ARGV[3], ARGV[2])
redis.call('XADD', KEYS[2], '*', 'id', ARGV[4])
return 'ok'
