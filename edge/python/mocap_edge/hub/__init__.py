"""The IMU hub: sensor nodes on CAN (python-can, frames decoded with cantools from the CAN
database in proto/can), every sample mapped onto the hub's clock (clock_fit), published as
ImuBatch."""
