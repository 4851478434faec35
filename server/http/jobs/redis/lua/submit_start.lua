-- Accepting a job and, when no other entry waits, starting it at once for this consumer (a local
-- worker slot is free): one write instead of two, and the input is not read back (element 4 of
-- the reply is empty). KEYS: stream, hash, input, idem.  ARGV: those of start_job, then id,
-- input, format, params, created_ms, capacity, fingerprint, has_key, client share key, client quota.
local r = submit(KEYS[2], KEYS[3], KEYS[1], KEYS[4], ARGV[11], ARGV[12], ARGV[13], ARGV[14], ARGV[15], ARGV[16],
                 ARGV[17], ARGV[5], ARGV[18], ARGV[10], ARGV[19], ARGV[20])
if r[1] ~= 'ok' or r[2] > 0 then return r end
local x = redis.call('XREADGROUP', 'GROUP', ARGV[5], ARGV[1], 'COUNT', '1', 'STREAMS', KEYS[1], '>')
if not x then return r end
return start_entry(x[1][2][1], false)
