-- Takes the next new entry for this consumer and starts its job, in one step (one write, one
-- round trip). Nothing new: {'none', ..., last entry id}, for XREAD BLOCK to wait after it.
local r = redis.call('XREADGROUP', 'GROUP', ARGV[5], ARGV[1], 'COUNT', '1', 'STREAMS', KEYS[1], '>')
if not r then
  local last = redis.call('XREVRANGE', KEYS[1], '+', '-', 'COUNT', '1')
  return {'none', 0, '', '', '', '', #last == 0 and '0-0' or last[1][1], ''}
end
return start_entry(r[1][2][1], true)
