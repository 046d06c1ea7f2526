import sys, time, resource, kryflex
def cpu():
    a, b = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return a.ru_utime + a.ru_stime + b.ru_utime + b.ru_stime
scene = kryflex.load_scene(sys.argv[1]); acc = float(sys.argv[2])
c0 = cpu()
out = kryflex.reduce(scene, quiet=True, accuracy=acc)
ch = out.summary.chosen
print("%s acc %g sizes %s error %.4g %s compressed %s->%s cpu (self + children) %.3f s, whole_s %.3f, search_s %.3f, compress_s %.3f" % (sys.argv[3], acc, out.model.sizes, out.summary.verdict.error_max, ch.method, ch.compressed_from_dofs, ch.compressed_to_dofs, cpu() - c0, out.summary.performance.whole_s, out.summary.performance.search_s, out.summary.performance.compress_s), flush=True)
