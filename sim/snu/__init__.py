"""rasterhw.sim.snu"""
