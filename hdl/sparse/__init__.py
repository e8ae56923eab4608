"""rasterhw.hdl.sparse"""
