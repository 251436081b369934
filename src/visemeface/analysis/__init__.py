"""visemeface.analysis"""
