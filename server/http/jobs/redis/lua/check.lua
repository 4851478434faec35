-- Between heartbeats, a read-only look (no write, so no fsync): still ours? cancelled?
-- KEYS: hash.  ARGV: consumer.
if redis.call('HGET', KEYS[1], 'owner') ~= ARGV[1] or redis.call('HGET', KEYS[1], 'state') ~= 'running' then
  return 'lost'
end
if redis.call('HGET', KEYS[1], 'cancel') == '1' then return 'cancel' end
return 'ok'
