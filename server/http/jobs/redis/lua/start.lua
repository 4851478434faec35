-- An entry taken over with XAUTOCLAIM (already in this consumer's pending list).
return start_job(ARGV[11], ARGV[12], true)
