"""A day's takes solved as one batch (`mocap batch`): each take (a take folder or a recording)
is a task on Dask distributed — calibrated, solved, exported and reported on a worker — on a
LocalCluster of this machine's cores or on a cluster given its scheduler's address."""
