"""visemeface.physics"""
