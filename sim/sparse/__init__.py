"""rasterhw.sim.sparse"""
