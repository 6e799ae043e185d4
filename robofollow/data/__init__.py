"""Demonstration datasets: recording expert episodes and writing LeRobot / HDF5 datasets."""
