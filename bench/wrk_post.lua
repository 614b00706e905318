-- wrk script: POST /v1/jobs with a small request that is different every time (a square
-- crossed by two segments, shifted by a counter), so none is served from the cache, and
-- Prefer: wait=5 so the response is the result.  Counts non-200 answers.
local counter = 0
local thread_id = 0
local non200 = 0

function setup(thread)
  thread:set("thread_id", thread_id)
  thread_id = thread_id + 1
end

function init(args)
  counter = thread_id * 1000000000
end

function request()
  counter = counter + 1
  local d = counter * 1e-3
  local body = string.format(
    '{"kind":"lines","lines":[[[%g,0],[%g,0]],[[%g,0],[%g,4]],[[%g,4],[%g,4]],[[%g,4],[%g,0]],' ..
    '[[%g,-1],[%g,5]],[[%g,5],[%g,-1]]]}',
    d, d + 4, d + 4, d + 4, d + 4, d, d, d, d - 1, d + 5, d - 1, d + 5)
  return wrk.format("POST", "/v1/jobs",
    {["Content-Type"] = "application/json", ["Prefer"] = "wait=5"}, body)
end

function response(status, headers, body)
  if status ~= 200 then non200 = non200 + 1 end
end

function done(summary, latency, requests)
  io.write(string.format("non-200 responses: %d (of %d)\n", summary.errors.status, summary.requests))
  io.write(string.format("p50 %.2f ms  p99 %.2f ms\n", latency:percentile(50) / 1000,
                         latency:percentile(99) / 1000))
end
