"""visemeface.postures"""
