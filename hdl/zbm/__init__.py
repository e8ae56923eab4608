"""rasterhw.hdl.zbm"""
