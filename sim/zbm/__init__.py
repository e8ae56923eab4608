"""rasterhw.sim.zbm"""
