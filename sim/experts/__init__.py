"""rasterhw.sim.experts"""
