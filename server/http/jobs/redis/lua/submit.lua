-- KEYS: hash, input, stream, idem.  ARGV: id, input, format, params, created_ms, capacity,
-- fingerprint, group, has_key, job key prefix, client share key ('' for none), client quota.
return submit(KEYS[1], KEYS[2], KEYS[3], KEYS[4], ARGV[1], ARGV[2], ARGV[3], ARGV[4], ARGV[5], ARGV[6], ARGV[7],
              ARGV[8], ARGV[9], ARGV[10], ARGV[11], ARGV[12])
