"""rasterhw.hdl"""
