-- Heartbeat. KEYS: hash, stream.  ARGV: consumer, stage ('' = unchanged), fraction, entry id, group.
if redis.call('HGET', KEYS[1], 'owner') ~= ARGV[1] or redis.call('HGET', KEYS[1], 'state') ~= 'running' then
  return 'lost'
end
if ARGV[2] ~= '' then redis.call('HSET', KEYS[1], 'stage', ARGV[2], 'fraction', ARGV[3]) end
redis.call('XCLAIM', KEYS[2], ARGV[5], ARGV[1], 0, ARGV[4], 'JUSTID')
if redis.call('HGET', KEYS[1], 'cancel') == '1' then return 'cancel' end
return 'ok'
