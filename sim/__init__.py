"""rasterhw.sim"""
