"""visemeface.muscles"""
