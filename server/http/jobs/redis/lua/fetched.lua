-- GET /v1/jobs/{id}/result answered 200: the result gives its client's slot up (decision 78).
-- KEYS: hash.
leave_share(KEYS[1])
return 'ok'
