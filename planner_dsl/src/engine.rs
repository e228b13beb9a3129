//! The sandboxed Rhai engine: `Engine::new_raw()` plus only arithmetic, logic,
//! strings, arrays, maps, basic maths, ranges and the robot function library; every
//! limit set; `eval`, `Fn`, `call`, `curry`, `print`, `debug` and reflection disabled.

use crate::error::Span;
use crate::limits::Limits;
use crate::registry::{registry, FunctionSpec};
use crate::value::{AgentHandle, ObjectRecord};
use rhai::packages::{
    ArithmeticPackage, BasicArrayPackage, BasicIteratorPackage, BasicMapPackage, BasicMathPackage,
    BasicStringPackage, LogicPackage, MoreStringPackage, Package,
};
use rhai::{
    Dynamic, Engine, EvalAltResult, FuncRegistration, Module, NativeCallContext, OptimizationLevel,
    Position, Shared,
};

type SharedModule = Shared<Module>;
type RhaiResultOf<T> = Result<T, Box<EvalAltResult>>;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, Sender};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Instant;

/// Symbols disabled at parse time: scripts using them fail to compile. (Other
/// unavailable names such as `print` or `sleep` are left to the validator, which
/// reports all of them at once with a hint.)
pub(crate) const DISABLED_SYMBOLS: &[&str] = &["eval", "Fn", "call", "curry", "import", "export"];

/// Token carried by `ErrorTerminated` when a library call failed (the host holds the
/// error itself).
pub(crate) const TOKEN_LIBRARY: &str = "library-call-failed";
/// Token carried by `ErrorTerminated` when the wall-clock deadline passed.
pub(crate) const TOKEN_DEADLINE: &str = "deadline";

/// A request from the script thread to the host thread, which owns the map and robot.
#[derive(Debug)]
pub(crate) enum Request {
    Call {
        spec: &'static FunctionSpec,
        args: Vec<Dynamic>,
        span: Span,
    },
    Done(Result<(), Box<EvalAltResult>>),
}

/// The host's answer: the call's result, or `Err` when the plan must stop.
pub(crate) type Response = Result<Dynamic, ()>;

/// The script side of a run: channels to the host, and time spent in library calls
/// (excluded from the script's deadline).
#[derive(Debug)]
pub(crate) struct Link {
    pub(crate) chan: Mutex<(Sender<Request>, Receiver<Response>)>,
    pub(crate) library_nanos: AtomicU64,
}

fn std_modules() -> &'static [SharedModule] {
    static MODULES: OnceLock<Vec<SharedModule>> = OnceLock::new();
    MODULES.get_or_init(|| {
        vec![
            ArithmeticPackage::new().as_shared_module(),
            LogicPackage::new().as_shared_module(),
            BasicStringPackage::new().as_shared_module(),
            MoreStringPackage::new().as_shared_module(),
            BasicArrayPackage::new().as_shared_module(),
            BasicMapPackage::new().as_shared_module(),
            BasicMathPackage::new().as_shared_module(),
            BasicIteratorPackage::new().as_shared_module(),
            library_module(),
        ]
    })
}

fn terminated(token: &str, pos: Position) -> Box<EvalAltResult> {
    Box::new(EvalAltResult::ErrorTerminated(
        Dynamic::from(token.to_string()),
        pos,
    ))
}

/// Sends one library call to the host and waits for its answer.
fn dispatch(
    ctx: &NativeCallContext<'_>,
    spec: &'static FunctionSpec,
    args: Vec<Dynamic>,
) -> RhaiResultOf<Dynamic> {
    let pos = ctx.call_position();
    let link = ctx
        .tag()
        .and_then(|t| t.clone().try_cast::<Arc<Link>>())
        .ok_or_else(|| {
            Box::new(EvalAltResult::ErrorRuntime(
                format!(
                    "{}: the robot function library is not available here",
                    spec.name
                )
                .into(),
                pos,
            ))
        })?;
    let start = Instant::now();
    let answer = {
        let guard = link
            .chan
            .lock()
            .map_err(|_| terminated(TOKEN_LIBRARY, pos))?;
        let (tx, rx) = &*guard;
        tx.send(Request::Call {
            spec,
            args,
            span: Span::from_position(pos),
        })
        .map_err(|_| terminated(TOKEN_LIBRARY, pos))?;
        rx.recv().map_err(|_| terminated(TOKEN_LIBRARY, pos))?
    };
    let nanos = u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX);
    link.library_nanos.fetch_add(nanos, Ordering::Relaxed);
    answer.map_err(|()| terminated(TOKEN_LIBRARY, pos))
}

fn reg<A: 'static, const N: usize, R, F>(m: &mut Module, name: &str, func: F)
where
    R: rhai::Variant + Clone,
    F: rhai::RhaiNativeFunc<A, N, true, R, true> + Send + Sync + 'static,
{
    FuncRegistration::new(name)
        .in_global_namespace()
        .with_purity(true)
        .with_volatility(true)
        .set_into_module(m, func);
}

/// Registers one library function at one arity, both as `f(...)` and as
/// `agent.f(...)`.
fn register_library_fn(m: &mut Module, spec: &'static FunctionSpec, arity: usize) {
    type Ctx<'a> = NativeCallContext<'a>;
    type H<'a> = &'a mut AgentHandle;
    // Rhai registers a native function per parameter count: one pair per arity.
    macro_rules! both_forms {
        ($($a:ident),*) => {{
            reg(m, spec.name, move |c: Ctx<'_>, $($a: Dynamic),*| {
                dispatch(&c, spec, vec![$($a),*])
            });
            reg(m, spec.name, move |c: Ctx<'_>, _: H<'_>, $($a: Dynamic),*| {
                dispatch(&c, spec, vec![$($a),*])
            });
        }};
    }
    match arity {
        0 => both_forms!(),
        1 => both_forms!(a),
        2 => both_forms!(a, b),
        3 => both_forms!(a, b, d),
        4 => both_forms!(a, b, d, e),
        5 => both_forms!(a, b, d, e, f),
        _ => both_forms!(a, b, d, e, f, g),
    }
}

/// The most arguments a library function may take ([`register_library_fn`] writes
/// each arity out; a registry test checks every function fits).
pub(crate) const MAX_LIBRARY_ARITY: usize = 6;

/// The robot function library as a Rhai module (built once).
fn library_module() -> SharedModule {
    let mut m = Module::new();
    m.set_custom_type::<ObjectRecord>("Object");
    m.set_custom_type::<AgentHandle>("Agent");
    for spec in registry() {
        for arity in spec.min_args()..=spec.max_args().min(MAX_LIBRARY_ARITY) {
            register_library_fn(&mut m, spec, arity);
        }
    }
    m.set_getter_fn("name", |o: &mut ObjectRecord| Ok(o.name.clone()));
    m.set_getter_fn("label", |o: &mut ObjectRecord| Ok(o.name.clone()));
    let colour =
        |o: &mut ObjectRecord| Ok(o.colour.clone().map(Dynamic::from).unwrap_or(Dynamic::UNIT));
    m.set_getter_fn("colour", colour);
    m.set_getter_fn("color", colour);
    m.set_getter_fn("label_id", |o: &mut ObjectRecord| Ok(i64::from(o.label_id)));
    m.set_getter_fn("id", |o: &mut ObjectRecord| Ok(i64::from(o.id)));
    m.set_getter_fn("count", |o: &mut ObjectRecord| Ok(i64::from(o.count)));
    m.set_getter_fn("position", |o: &mut ObjectRecord| {
        Ok(crate::value::point_to_dynamic(o.position))
    });
    m.set_native_fn("to_string", |o: &mut ObjectRecord| Ok(o.to_string()));
    m.set_native_fn("to_debug", |o: &mut ObjectRecord| Ok(format!("{o:?}")));
    m.set_native_fn("to_string", |_: &mut AgentHandle| Ok("agent".to_string()));
    m.set_native_fn("to_debug", |_: &mut AgentHandle| Ok("agent".to_string()));
    m.set_native_fn("==", |a: &mut ObjectRecord, b: ObjectRecord| {
        Ok(a.id == b.id)
    });
    m.set_native_fn("!=", |a: &mut ObjectRecord, b: ObjectRecord| {
        Ok(a.id != b.id)
    });
    m.into()
}

/// A sandboxed engine with `limits` (no run context: library calls fail).
pub(crate) fn sandbox(limits: &Limits) -> Engine {
    let mut e = Engine::new_raw();
    for m in std_modules() {
        e.register_global_module(m.clone());
    }
    limits.apply(&mut e);
    for s in DISABLED_SYMBOLS {
        e.disable_symbol(*s);
    }
    e.set_optimization_level(OptimizationLevel::None);
    e.set_fail_on_invalid_map_property(true);
    e.set_allow_looping(true);
    // Undefined variables are compile errors (before the robot moves), not
    // failures half-way through a plan.
    e.set_strict_variables(true);
    // `agent` resolves everywhere, also inside script-defined functions.
    #[allow(deprecated)] // volatile API, not deprecated (Rhai's own note)
    e.on_var(|name, _, _| {
        Ok((name == "agent").then(|| Dynamic::from(AgentHandle).into_read_only()))
    });
    e
}

/// The scope plans are compiled against: just the constant `agent` (so strict
/// variables accepts it; at run time `on_var` supplies it, also inside functions).
pub(crate) fn compile_scope() -> rhai::Scope<'static> {
    let mut scope = rhai::Scope::new();
    scope.push_constant("agent", AgentHandle);
    scope
}

/// The engine used to compile with default limits (built once).
pub(crate) fn default_compiler() -> &'static Engine {
    static ENGINE: OnceLock<Engine> = OnceLock::new();
    ENGINE.get_or_init(|| sandbox(&Limits::default()))
}

/// A sandboxed engine wired to a run: library calls go through `link`, and the
/// script's own time (total minus time in library calls) is held to the deadline.
pub(crate) fn for_run(limits: &Limits, link: Arc<Link>, operations: Arc<AtomicU64>) -> Engine {
    let mut e = sandbox(limits);
    let start = Instant::now();
    let deadline = u64::try_from(limits.deadline.as_nanos()).unwrap_or(u64::MAX);
    let timing = link.clone();
    e.set_default_tag(Dynamic::from(link));
    e.on_progress(move |ops| {
        operations.store(ops, Ordering::Relaxed);
        if ops % 64 != 0 {
            return None;
        }
        let total = u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX);
        let script = total.saturating_sub(timing.library_nanos.load(Ordering::Relaxed));
        (script > deadline).then(|| Dynamic::from(TOKEN_DEADLINE.to_string()))
    });
    e
}
