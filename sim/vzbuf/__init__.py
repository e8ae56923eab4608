"""rasterhw.sim.vzbuf"""
