-- Every replica that ever ran is a consumer of the group; a restarted one comes back under a new
-- name. Consumers with nothing pending and idle for ARGV[2] ms are deleted, atomically (a
-- consumer deleted with an entry pending would strand it). A live one idle that long is simply
-- re-created by its next XREADGROUP. KEYS: stream.  ARGV: group, idle_ms.
local n = 0
for _, c in ipairs(redis.call('XINFO', 'CONSUMERS', KEYS[1], ARGV[1])) do
  local f = {}
  for i = 1, #c, 2 do f[c[i]] = c[i + 1] end
  if f['pending'] == 0 and f['idle'] > tonumber(ARGV[2]) then
    redis.call('XGROUP', 'DELCONSUMER', KEYS[1], ARGV[1], f['name'])
    n = n + 1
  end
end
return n
