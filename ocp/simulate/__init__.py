"""Forward simulation of a plant: open loop under a given input, and the paper's closed loop."""
