"""cocotb bench for the SNU pixel-bus controller."""
