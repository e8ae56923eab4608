"""rasterhw.hdl.vzbuf"""
