"""visemeface.face"""
