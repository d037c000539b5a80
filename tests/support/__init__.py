"""Helpers shared by the tests and benchmarks: data paths, synthetic motions and songs, fakes of the network peers."""
