"""Recordings of the streams: MCAP files written from ZeroMQ publishers (`record`), read
back (`read`), replayed on ZeroMQ (`replay`) and solved offline through the live host's
own pipeline (`offline`)."""
