"""rasterhw.hdl.snu"""
