"""rasterhw.hdl.experts"""
